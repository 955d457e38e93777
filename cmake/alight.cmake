# Small helpers shared by every component's CMakeLists.txt.

# ccache (Debian's package; scripts/setup installs it): a rebuild after switching branches or
# touching a widely included header recompiles only what really changed, and a second clone on
# the same machine compiles almost nothing. A fresh machine starts with an empty cache, so this
# speeds repeat builds only. Precompiled headers stay cacheable with what ccache's manual asks
# for: the sloppiness pch_defines, time_macros (include_file_mtime/ctime because the .gch is
# rebuilt moments before its users compile) and, with GCC, -fpch-preprocess on their users
# (alight_use_pch). CCACHE_BASEDIR makes the paths inside this tree relative, so two clones'
# compile lines are the same (the trees' own paths live in alight_build_paths, not in -D flags).
option(ALIGHT_CCACHE "Compile through ccache when it is installed" ON)
find_program(ALIGHT_CCACHE_PROGRAM ccache)
if(ALIGHT_CCACHE AND ALIGHT_CCACHE_PROGRAM AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  set(CMAKE_CXX_COMPILER_LAUNCHER
      ${CMAKE_COMMAND} -E env
      "CCACHE_SLOPPINESS=pch_defines,time_macros,include_file_mtime,include_file_ctime"
      "CCACHE_BASEDIR=${PROJECT_SOURCE_DIR}"
      ${ALIGHT_CCACHE_PROGRAM})
endif()

# lld (Debian's package; scripts/setup installs it) links in about a third of the CPU time of
# GNU ld, and every test binary and node links the same static libraries and OpenCV again.
option(ALIGHT_LLD "Link with lld when the compiler can" ON)
if(ALIGHT_LLD)
  include(CheckLinkerFlag)
  check_linker_flag(CXX -fuse-ld=lld ALIGHT_HAVE_LLD)
  if(ALIGHT_HAVE_LLD)
    add_link_options(-fuse-ld=lld)
  endif()
endif()

# A program records only the shared libraries it uses. Each test suite (each case of an
# integration binary) runs in a process of its own, and OpenCV's image codecs alone load about
# 130 libraries (GDAL, HDF5, Poppler, ...), whose relocation costs about a tenth of a CPU second
# a process.
add_link_options(LINKER:--as-needed)

# Precompiled headers. Each test and node translation unit otherwise parses GoogleTest, CLI11,
# spdlog, Eigen, OpenCV's core and yaml-cpp again; the build is dominated by that parsing. One
# header set per kind is compiled once (the targets alight_pch_test / alight_pch_node, with the
# same flags as their users) and every test or node reuses it. GCC uses a precompiled header
# only when it was built with compatible flags and falls back to the plain headers otherwise
# (-Winvalid-pch says so), so a target with other flags still builds the same code.
option(ALIGHT_PCH "Precompile the external headers of tests and nodes" ON)
set(ALIGHT_PCH_COMMON_HEADERS <Eigen/Core> <Eigen/Geometry> <opencv2/core.hpp> <yaml-cpp/yaml.h>
    <algorithm> <chrono> <cmath> <cstdint> <cstdio> <filesystem> <fstream> <functional> <map>
    <memory> <optional> <random> <sstream> <string> <thread> <vector>)
set(ALIGHT_PCH_ANCHOR ${CMAKE_CURRENT_LIST_DIR}/pch_anchor.cpp)

# alight_pch_target(NAME HEADERS ... LIBS ...): the object library that owns one header set.
# alight_use_pch(TARGET NAME) makes TARGET reuse it, with the same libraries (their include
# folders and definitions, e.g. spdlog's SPDLOG_COMPILED_LIB, must be those the set was built
# with, and GCC falls back to the headers themselves if anything differs).
function(alight_pch_target name)
  cmake_parse_arguments(ARG "" "" "HEADERS;LIBS" ${ARGN})
  add_library(${name} OBJECT ${ALIGHT_PCH_ANCHOR})
  set(libs ${ARG_LIBS} Eigen3::Eigen opencv_core yaml-cpp)
  target_link_libraries(${name} PRIVATE ${libs})
  set_target_properties(${name} PROPERTIES ALIGHT_PCH_LIBS "${libs}")
  alight_light_optimisation(${name})
  target_precompile_headers(${name} PRIVATE ${ARG_HEADERS} ${ALIGHT_PCH_COMMON_HEADERS})
endfunction()

function(alight_use_pch target pch)
  if(TARGET ${pch})
    get_target_property(libs ${pch} ALIGHT_PCH_LIBS)
    target_link_libraries(${target} PRIVATE ${libs})
    target_precompile_headers(${target} REUSE_FROM ${pch})
    if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
      target_compile_options(${target} PRIVATE -fpch-preprocess)
    endif()
  endif()
endfunction()

# alight_light_sources(file ...): files of the current folder that read and validate parameters
# (ParamSchema's templates and yaml-cpp: slow to compile, run once at start-up) compile at -O1 in
# Release, whatever their library's level.
function(alight_light_sources)
  if(CMAKE_BUILD_TYPE STREQUAL "Release" AND CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    set_source_files_properties(${ARGN} DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}
                                PROPERTIES COMPILE_OPTIONS -O1)
  endif()
endfunction()

# Tests and nodes compile at -O1 in Release (see alight_add_gtest, alight_add_node).
function(alight_light_optimisation name)
  if(CMAKE_BUILD_TYPE STREQUAL "Release" AND CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${name} PRIVATE -O1)
  endif()
endfunction()

# Where this tree was configured (common/build_paths.hpp): one generated file instead of -D
# definitions on every test's and bench's compile line, which would differ between two clones
# and defeat ccache for every object of theirs.
configure_file(${CMAKE_CURRENT_LIST_DIR}/build_paths.cpp.in ${CMAKE_BINARY_DIR}/generated/build_paths.cpp
               @ONLY)
add_library(alight_build_paths STATIC ${CMAKE_BINARY_DIR}/generated/build_paths.cpp)
target_include_directories(alight_build_paths PUBLIC ${PROJECT_SOURCE_DIR})

if(ALIGHT_PCH AND NOT ALIGHT_BUILD_FUZZ)
  alight_pch_target(alight_pch_node HEADERS <CLI/CLI.hpp> <spdlog/spdlog.h> <lcm/lcm-cpp.hpp>
                    LIBS CLI11::CLI11 spdlog::spdlog lcm::lcm)
endif()

option(ALIGHT_UNITY_TESTS "Compile each test binary's files in batches (unity build)" ON)

# alight_unit_test_needs(target ...): targets the unit tests run, built by the target
# alight_unit_tests (test/CMakeLists.txt; `scripts/test --quick` builds only that).
function(alight_unit_test_needs)
  set_property(GLOBAL APPEND PROPERTY ALIGHT_UNIT_TEST_TARGETS ${ARGN})
endfunction()

# alight_unity_sources(OUT NAME file ...): with ALIGHT_UNITY_TESTS, a test binary's files compile
# a few at a time as one translation unit, so GoogleTest's, Eigen's and the fixtures' templates
# are instantiated and compiled once per batch instead of once per file (the simulator's nine
# files: 51 CPU seconds apart, 23 as one). A file's names in its anonymous namespace are then
# visible to the next files of its batch: test files give their file-local constants and helpers
# distinct names. The batch files are written here rather than by CMake's UNITY_BUILD because
# CMake (before 3.27) includes the files by absolute path: every batch would differ between two
# clones and miss ccache; these include them relative to the repository's root.
function(alight_unity_sources out name)
  set(files ${ARGN})
  list(LENGTH files count)
  if(NOT ALIGHT_UNITY_TESTS OR count LESS 2)
    set(${out} ${files} PARENT_SCOPE)
    return()
  endif()
  set(batches "")
  math(EXPR last "${count} - 1")
  foreach(start RANGE 0 ${last} 8)
    list(SUBLIST files ${start} 8 batch_files)
    set(text "// Generated by alight_unity_sources.\n")
    foreach(file IN LISTS batch_files)
      get_filename_component(abs ${file} ABSOLUTE BASE_DIR ${CMAKE_CURRENT_SOURCE_DIR})
      file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${abs})
      string(APPEND text "#include \"${rel}\"\n")
    endforeach()
    math(EXPR index "${start} / 8")
    set(batch ${CMAKE_CURRENT_BINARY_DIR}/${name}_unity_${index}.cpp)
    file(CONFIGURE OUTPUT ${batch} CONTENT "${text}")
    list(APPEND batches ${batch})
  endforeach()
  set(${out} ${batches} PARENT_SCOPE)
endfunction()

# alight_add_gtest(NAME SOURCES a.cpp b.cpp LIBS lib1 lib2 [LABELS l1 l2] [TIMEOUT s]
#                  [RESOURCE_LOCK name] [INTEGRATION] [COST c])
# One GoogleTest binary in build/bin/tests. A unit binary (label unit: `scripts/test --quick`
# runs -L unit) is registered with CTest one suite at a time, `<binary>:<Suite>` (see
# gtest_suites.cmake: a process's start-up costs more than most unit cases); an INTEGRATION one
# (processes over LCM, flights in real time or many simulated ones, other programs) one case at
# a time, so its long cases run in parallel.
# TIMEOUT: seconds per case (a suite gets it times its number of cases).
# RESOURCE_LOCK: tests that share something (a fixed LCM port) never run at the same time.
# COST: CTest starts costly tests first (a fresh tree has no timings of its own), so the long
# ones do not end up alone on one core at the end of the run.
function(alight_add_gtest name)
  cmake_parse_arguments(ARG "INTEGRATION" "TIMEOUT;RESOURCE_LOCK;COST" "SOURCES;LIBS;LABELS"
                        ${ARGN})
  alight_unity_sources(sources ${name} ${ARG_SOURCES})
  add_executable(${name} ${sources})
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} alight_build_paths GTest::gtest GTest::gtest_main)
  # The code under test is in the libraries, built as configured; a test's own translation units
  # (GoogleTest's macros, fixtures) gain little from -O2 and compile much faster at -O1.
  alight_light_optimisation(${name})
  alight_use_pch(${name} alight_pch_test)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bin/tests)
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 120)
  endif()
  set(labels ${ARG_LABELS})
  if(NOT ARG_INTEGRATION)
    list(APPEND labels unit)
    alight_unit_test_needs(${name})
    # Listed when ctest runs (as PRE_TEST discovery), not after each link.
    set(file ${CMAKE_CURRENT_BINARY_DIR}/${name}_suites.cmake)
    string(CONCAT content
      "set(_alight_exe [==[$<TARGET_FILE:${name}>]==])\n"
      "set(_alight_name [==[${name}]==])\n"
      "set(_alight_list [==[${CMAKE_CURRENT_BINARY_DIR}/${name}_suites.txt]==])\n"
      "set(_alight_dir [==[${CMAKE_CURRENT_BINARY_DIR}]==])\n"
      "set(_alight_labels [==[${labels}]==])\n"
      "set(_alight_timeout ${ARG_TIMEOUT})\n"
      "set(_alight_lock [==[${ARG_RESOURCE_LOCK}]==])\n"
      "set(_alight_cost [==[${ARG_COST}]==])\n"
      "include([==[${PROJECT_SOURCE_DIR}/cmake/gtest_suites.cmake]==])\n")
    file(GENERATE OUTPUT ${file} CONTENT "${content}")
    set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${file})
    return()
  endif()
  list(APPEND labels integration)
  set(properties TIMEOUT ${ARG_TIMEOUT})
  if(ARG_RESOURCE_LOCK)
    list(APPEND properties RESOURCE_LOCK ${ARG_RESOURCE_LOCK})
  endif()
  if(ARG_COST)
    list(APPEND properties COST ${ARG_COST})
  endif()
  # PRE_TEST: the cases are listed when ctest runs, not after each link, so the build never
  # waits on a test binary starting (and a build without ctest never runs one).
  gtest_discover_tests(${name} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60
    TEST_LIST ${name}_TESTS PROPERTIES ${properties})
  # The labels are set by a file CTest reads after the discovered list: passed through
  # PROPERTIES, a list of labels would be flattened into separate arguments, all but the first
  # read as property names.
  set(file ${CMAKE_CURRENT_BINARY_DIR}/${name}_labels.cmake)
  file(WRITE ${file}
    "if(${name}_TESTS)\n"
    "  set_tests_properties(\${${name}_TESTS} PROPERTIES LABELS \"${labels}\")\n"
    "endif()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${file})
endfunction()

# alight_add_node(BINARY_NAME SOURCES ... LIBS ...): build/bin/alight-<name>.
function(alight_add_node name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS})
  # A node is glue (options, LCM, timers) around its library, which does the work at the
  # configured optimisation; -O1 halves the cost of compiling CLI11 and spdlog into each one.
  alight_light_optimisation(${name})
  alight_use_pch(${name} alight_pch_node)
endfunction()
