# Read by CTest (a TEST_INCLUDE_FILES entry that alight_add_gtest writes for each unit test
# binary): one CTest test per GoogleTest suite, `<binary>:<Suite>` running `--gtest_filter=Suite.*`.
#
# Why per suite and not per case: a test process's start-up (the dynamic linker relocating
# OpenCV and the other shared libraries) costs more CPU than most unit cases themselves, and
# the test command is CPU-bound on two cores. The integration binaries (flights, LCM, real time)
# keep one CTest test per case (gtest_discover_tests): their cases are long and run in parallel.
#
# Set before this file is included:
#   _alight_exe      the test binary
#   _alight_name     its target name (the tests' prefix)
#   _alight_list     where the suite list is kept between runs
#   _alight_dir      the tests' working directory
#   _alight_labels   CTest labels of every suite
#   _alight_timeout  seconds per case (a suite gets this times its number of cases)
#   _alight_lock     RESOURCE_LOCK, or empty
#   _alight_cost     COST per case, or empty
# A suite with a skipped case (GTEST_SKIP) passes, the skip in its output: a SKIP_REGULAR_EXPRESSION
# would mark the whole suite skipped, a failing case beside it included.
# The list is made again whenever the binary is newer than it, as gtest_discover_tests'
# PRE_TEST mode does: `ctest` right after a build lists what that build holds.

if(NOT EXISTS "${_alight_exe}")
  # A binary not built: a test that fails and says so (what gtest_discover_tests does too).
  add_test("${_alight_name}_NOT_BUILT" "${_alight_name}_NOT_BUILT")
  return()
endif()

if(NOT EXISTS "${_alight_list}" OR "${_alight_exe}" IS_NEWER_THAN "${_alight_list}")
  execute_process(COMMAND "${_alight_exe}" --gtest_list_tests
                  WORKING_DIRECTORY "${_alight_dir}" TIMEOUT 60
                  OUTPUT_VARIABLE _alight_out ERROR_VARIABLE _alight_err
                  RESULT_VARIABLE _alight_rc)
  if(NOT _alight_rc EQUAL 0)
    message(FATAL_ERROR
            "${_alight_exe} --gtest_list_tests failed (${_alight_rc}):\n${_alight_out}${_alight_err}")
  endif()
  # gtest's listing: "Suite." (perhaps "  # TypeParam = ...") then its cases indented by two.
  string(REPLACE ";" "\\;" _alight_out "${_alight_out}")
  string(REPLACE "\n" ";" _alight_lines "${_alight_out}")
  set(_alight_suite "")
  set(_alight_entries "")
  set(_alight_count 0)
  foreach(_alight_line IN LISTS _alight_lines)
    if(_alight_line MATCHES "^([^ #][^ ]*)\\.( +#.*)?$")
      if(_alight_suite AND _alight_count GREATER 0)
        string(APPEND _alight_entries "${_alight_suite} ${_alight_count}\n")
      endif()
      set(_alight_suite "${CMAKE_MATCH_1}")
      set(_alight_count 0)
      if(_alight_suite MATCHES "(^|/)DISABLED_")
        set(_alight_suite "")
      endif()
    elseif(_alight_suite AND _alight_line MATCHES "^  ([^ ]+)( +#.*)?$")
      if(NOT CMAKE_MATCH_1 MATCHES "^DISABLED_")
        math(EXPR _alight_count "${_alight_count} + 1")
      endif()
    endif()
  endforeach()
  if(_alight_suite AND _alight_count GREATER 0)
    string(APPEND _alight_entries "${_alight_suite} ${_alight_count}\n")
  endif()
  file(WRITE "${_alight_list}" "${_alight_entries}")
endif()

file(STRINGS "${_alight_list}" _alight_entries)
foreach(_alight_entry IN LISTS _alight_entries)
  string(REGEX MATCH "^([^ ]+) ([0-9]+)$" _alight_ok "${_alight_entry}")
  if(NOT _alight_ok)
    message(FATAL_ERROR "${_alight_list}: unreadable line '${_alight_entry}' (delete the file)")
  endif()
  set(_alight_suite "${CMAKE_MATCH_1}")
  set(_alight_count "${CMAKE_MATCH_2}")
  set(_alight_test "${_alight_name}:${_alight_suite}")
  add_test("${_alight_test}" "${_alight_exe}" "--gtest_filter=${_alight_suite}.*")
  math(EXPR _alight_seconds "${_alight_timeout} * ${_alight_count}")
  set_tests_properties("${_alight_test}" PROPERTIES
                       WORKING_DIRECTORY "${_alight_dir}" TIMEOUT ${_alight_seconds}
                       LABELS "${_alight_labels}")
  if(_alight_lock)
    set_tests_properties("${_alight_test}" PROPERTIES RESOURCE_LOCK "${_alight_lock}")
  endif()
  if(_alight_cost)
    math(EXPR _alight_total "${_alight_cost} * ${_alight_count}")
    set_tests_properties("${_alight_test}" PROPERTIES COST ${_alight_total})
  endif()
endforeach()
