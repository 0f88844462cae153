// The main of every test program: GoogleTest's own, but a run in which no test passed is never
// exit 0. GoogleTest exits 0 when every selected test called GTEST_SKIP(), and CTest reads only its
// SKIP_RETURN_CODE (77) as "Skipped": a program run whole by add_test (the networked tests, many
// tests in one CTest case) whose tests all skipped would read as "Passed". So:
//   a failure                      -> GoogleTest's status (1)
//   at least one test passed       -> 0 (the others' skips are in the output, each with its reason)
//   none passed, some skipped      -> 77: CTest's "Skipped" (the reasons are in the output above)
//   no test selected at all        -> 1: a filter that matches nothing tests nothing
// Listing (--gtest_list_tests, as gtest_discover_tests does) runs nothing and exits 0.
#include <cstdio>

#include <gtest/gtest.h>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  const int status = RUN_ALL_TESTS();
  if (status != 0 || GTEST_FLAG_GET(list_tests)) return status;
  const auto& run = *::testing::UnitTest::GetInstance();
  if (run.successful_test_count() > 0) return 0;
  if (run.skipped_test_count() > 0) {
    std::printf("every selected test skipped (each with its reason above): exit 77, CTest's Skipped\n");
    return 77;
  }
  std::fprintf(stderr, "no test selected (--gtest_filter matches none): nothing was tested\n");
  return 1;
}
