// The doctest runner shared by krs_tests and krs_tests_native; test cases live in test_*.cpp.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>
