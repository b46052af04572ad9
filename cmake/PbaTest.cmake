# pba_test(NAME SOURCES ... [LABELS ...] [LIBS ...] [TIMEOUT seconds]
#          [RESOURCE_LOCK name])
# The one way tests are registered: a GoogleTest executable, discovered by ctest
# test by test, labelled unit / verification / hard / integration / slow /
# slurm (one label each: gtest_discover_tests passes them on unquoted). Tests
# sharing a RESOURCE_LOCK never run at the same time.
include(GoogleTest)
find_package(GTest REQUIRED)

function(pba_test name)
  cmake_parse_arguments(ARG "" "TIMEOUT;RESOURCE_LOCK" "SOURCES;LABELS;LIBS" ${ARGN})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 120)
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main GTest::gmock)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  if(ARG_RESOURCE_LOCK)
    gtest_discover_tests(${name}
      PROPERTIES LABELS "${ARG_LABELS}" TIMEOUT ${ARG_TIMEOUT} RESOURCE_LOCK ${ARG_RESOURCE_LOCK}
      DISCOVERY_TIMEOUT 60)
  else()
    gtest_discover_tests(${name}
      PROPERTIES LABELS "${ARG_LABELS}" TIMEOUT ${ARG_TIMEOUT}
      DISCOVERY_TIMEOUT 60)
  endif()
endfunction()
