# Registers the GoogleTest cases of TEST_EXECUTABLE with ctest by suite, for the sanitizer build:
# one process per suite (a suite of over SHARD_SIZE cases in shards of about that many, by
# GoogleTest's GTEST_TOTAL_SHARDS / GTEST_SHARD_INDEX) instead of one per case. Under ASan a
# process of the test binary takes about 0.6 s to start and stop on the CI machine (page faults of
# its 135 MB), which was over 300 s of the stage's 1,150 s of test time (docs/reliability.md, "CI").
# Run after each build of the tests (tests/CMakeLists.txt): cmake -DTEST_EXECUTABLE=...
# -DOUTPUT=... -DTIMEOUT=... -DSHARD_SIZE=... -P suites.cmake
execute_process(COMMAND "${TEST_EXECUTABLE}" --gtest_list_tests
                OUTPUT_VARIABLE listing RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "${TEST_EXECUTABLE} --gtest_list_tests failed (${status})")
endif()
string(REPLACE "\n" ";" lines "${listing}")
set(suites)
foreach(line IN LISTS lines)
  if(line MATCHES "^([^ #][^ ]*)\\.")  # "Suite.  # TypeParam = ..." or "Suite."
    set(suite "${CMAKE_MATCH_1}")
    list(APPEND suites "${suite}")
    set("count_${suite}" 0)
  elseif(line MATCHES "^  [^ ]")
    math(EXPR "count_${suite}" "${count_${suite}} + 1")
  endif()
endforeach()
set(text "# Written by tests/suites.cmake from ${TEST_EXECUTABLE} --gtest_list_tests.\n")
foreach(suite IN LISTS suites)
  set(n "${count_${suite}}")
  math(EXPR shards "(${n} + ${SHARD_SIZE} - 1) / ${SHARD_SIZE}")
  if(shards LESS_EQUAL 1)
    string(APPEND text "add_test([==[${suite}]==] [==[${TEST_EXECUTABLE}]==] [==[--gtest_filter=${suite}.*]==])\n"
                       "set_tests_properties([==[${suite}]==] PROPERTIES TIMEOUT ${TIMEOUT})\n")
  else()
    math(EXPR last "${shards} - 1")
    foreach(i RANGE ${last})
      math(EXPR shown "${i} + 1")
      set(name "${suite} [${shown}/${shards}]")
      string(APPEND text "add_test([==[${name}]==] [==[${TEST_EXECUTABLE}]==] [==[--gtest_filter=${suite}.*]==])\n"
                         "set_tests_properties([==[${name}]==] PROPERTIES TIMEOUT ${TIMEOUT} ENVIRONMENT "
                         "[==[GTEST_TOTAL_SHARDS=${shards};GTEST_SHARD_INDEX=${i}]==])\n")
    endforeach()
  endif()
endforeach()
file(WRITE "${OUTPUT}" "${text}")
