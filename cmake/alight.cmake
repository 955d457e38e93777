# Small helpers shared by every component's CMakeLists.txt.

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
  if(CMAKE_BUILD_TYPE STREQUAL "Release" AND CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${name} PRIVATE -O1)
  endif()
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
  if(CMAKE_BUILD_TYPE STREQUAL "Release" AND CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${name} PRIVATE -O1)
  endif()
endfunction()
