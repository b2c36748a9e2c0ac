# Run after a test binary is linked (tests/CMakeLists.txt, aerotrack_test): lists its gtest cases and
# writes a CTest file with one test per gtest *suite*, `<binary>:<Suite>`, which runs the binary once with
# --gtest_filter=<Suite>.*. Why not one test per case (CMake's gtest_discover_tests): a process start costs
# 0.4-0.9 s under ASan in a binary that links OpenCV's imgcodecs or videoio (Debian's pull in about 140 and
# 250 shared libraries: GDAL, GDCM, FFmpeg, ...), and the unit binaries' cases take milliseconds, so one
# process per case spent about a third of the suite's CPU time starting processes (docs/testing.md,
# "CI time budget").
# Inputs (-D): TEST_EXECUTABLE, TEST_TARGET, TEST_LABELS, TEST_TIMEOUT, TEST_WORKING_DIR, CTEST_FILE.
cmake_minimum_required(VERSION 3.25)

execute_process(
  COMMAND "${TEST_EXECUTABLE}" --gtest_list_tests
  WORKING_DIRECTORY "${TEST_WORKING_DIR}"
  TIMEOUT 60
  OUTPUT_VARIABLE listing
  ERROR_VARIABLE errors
  RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  file(REMOVE "${CTEST_FILE}")
  message(FATAL_ERROR "${TEST_TARGET}: --gtest_list_tests failed (${status}): ${errors}")
endif()

# gtest's listing: a suite line "Suite." (a parameterised one "Prefix/Suite.", a typed one followed by
# "  # TypeParam = ..."), then its cases indented by two spaces.
string(REPLACE "\n" ";" lines "${listing}")
set(script "")
set(suites 0)
foreach(line IN LISTS lines)
  if(line MATCHES "^([^ #][^ ]*)\\.( .*)?$")
    set(suite "${CMAKE_MATCH_1}")
    string(APPEND script
      "add_test([==[${TEST_TARGET}:${suite}]==] [==[${TEST_EXECUTABLE}]==] [==[--gtest_filter=${suite}.*]==])\n"
      "set_tests_properties([==[${TEST_TARGET}:${suite}]==] PROPERTIES LABELS [==[${TEST_LABELS}]==]"
      " TIMEOUT ${TEST_TIMEOUT} WORKING_DIRECTORY [==[${TEST_WORKING_DIR}]==])\n")
    math(EXPR suites "${suites} + 1")
  endif()
endforeach()
if(suites EQUAL 0)
  file(REMOVE "${CTEST_FILE}")
  message(FATAL_ERROR "${TEST_TARGET}: no gtest suite in its --gtest_list_tests output")
endif()
file(WRITE "${CTEST_FILE}" "${script}")
