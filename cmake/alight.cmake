# Small helpers shared by every component's CMakeLists.txt.

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

if(ALIGHT_PCH AND NOT ALIGHT_BUILD_FUZZ)
  alight_pch_target(alight_pch_node HEADERS <CLI/CLI.hpp> <spdlog/spdlog.h> <lcm/lcm-cpp.hpp>
                    LIBS CLI11::CLI11 spdlog::spdlog lcm::lcm)
endif()

# alight_add_gtest(NAME SOURCES a.cpp b.cpp LIBS lib1 lib2 [LABELS l1] [TIMEOUT s]
#                  [RESOURCE_LOCK name])
# One GoogleTest binary in build/bin/tests, its cases registered with CTest one by one.
# RESOURCE_LOCK: cases that share something (a fixed LCM port) never run at the same time.
function(alight_add_gtest name)
  cmake_parse_arguments(ARG "" "TIMEOUT;RESOURCE_LOCK" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main)
  # The code under test is in the libraries, built as configured; a test's own translation units
  # (GoogleTest's macros, fixtures) gain little from -O2 and compile much faster at -O1.
  alight_light_optimisation(${name})
  alight_use_pch(${name} alight_pch_test)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bin/tests)
  target_compile_definitions(${name} PRIVATE
    ALIGHT_SOURCE_DIR="${PROJECT_SOURCE_DIR}" ALIGHT_BINARY_DIR="${CMAKE_BINARY_DIR}")
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 120)
  endif()
  set(lock "")
  if(ARG_RESOURCE_LOCK)
    set(lock RESOURCE_LOCK ${ARG_RESOURCE_LOCK})
  endif()
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60
    PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}" ${lock})
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
