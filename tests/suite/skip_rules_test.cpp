// A test that did not run never reads as passed: every CTest case of the suite declares exit 77 as
// Skipped (the check below reads the whole suite as ctest itself has it, so a case added later
// without cvo_add_test / cvo_add_command_test fails here by name), and every test program exits 77
// when none of its tests passed but some skipped (tests/support/test_main.cpp).
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace {

using cvo::testing::run_program;
using cvo::testing::ToolRun;

const std::filesystem::path kOutcomes = std::filesystem::path(CVO_TOOLS_DIR) / "suite_outcomes_program";

ToolRun run_outcomes(const std::string& filter, const cvo::test::TempDir& dir) {
  return run_program(kOutcomes, "--gtest_filter=" + filter, dir.path());
}

// The value of a test's property in ctest's json-v1 listing, or null.
nlohmann::json property(const nlohmann::json& test, const std::string& name) {
  for (const auto& p : test.value("properties", nlohmann::json::array()))
    if (p.at("name") == name) return p.at("value");
  return nullptr;
}

TEST(Suite, EveryRegisteredCaseReportsSkippedByExit77) {
  const cvo::test::TempDir dir;
  const ToolRun listing =
      run_program(CVO_CTEST_COMMAND, "--test-dir '" CVO_BUILD_DIR "' --show-only=json-v1", dir.path());
  ASSERT_EQ(listing.exit_code, 0) << listing.err;
  const auto json = nlohmann::json::parse(listing.out);
  std::string without;
  std::size_t checked = 0;
  for (const auto& test : json.at("tests")) {
    const std::string name = test.at("name");
    // CMake's stand-in for a test program not built yet: it fails when run, never passes.
    if (name.ends_with("_NOT_BUILT")) continue;
    ++checked;
    if (property(test, "SKIP_RETURN_CODE") != 77) without += "\n  " + name;
  }
  EXPECT_GT(checked, 1U) << "the listing holds this test at least";
  EXPECT_TRUE(without.empty()) << "cases that would read a skip as passed or failed (register them with cvo_add_test"
                               << " or cvo_add_command_test, tests/CMakeLists.txt):" << without;
}

TEST(TestMain, ARunWhoseEveryTestSkippedExits77WithTheReason) {
  const cvo::test::TempDir dir;
  const ToolRun run = run_outcomes("Outcome.SkipsForAReason", dir);
  EXPECT_EQ(run.exit_code, 77) << run.out << run.err;
  EXPECT_NE(run.out.find("needs a camera that is not here"), std::string::npos) << run.out;
}

TEST(TestMain, ARunWhereOneTestPassedExits0BesideSkips) {
  const cvo::test::TempDir dir;
  const ToolRun run = run_outcomes("Outcome.Passes:Outcome.SkipsForAReason", dir);
  EXPECT_EQ(run.exit_code, 0) << run.out << run.err;
}

TEST(TestMain, AFailureExits1BesideSkipsAndPasses) {
  const cvo::test::TempDir dir;
  EXPECT_EQ(run_outcomes("Outcome.SkipsForAReason:Outcome.Fails", dir).exit_code, 1);
  EXPECT_EQ(run_outcomes("Outcome.*", dir).exit_code, 1);
}

TEST(TestMain, AFilterThatSelectsNoTestExits1) {
  const cvo::test::TempDir dir;
  const ToolRun run = run_outcomes("Outcome.NoSuchTest", dir);
  EXPECT_EQ(run.exit_code, 1) << run.out;
  EXPECT_NE(run.err.find("no test selected"), std::string::npos) << run.err;
}

TEST(TestMain, ListingTheTestsExits0) {
  const cvo::test::TempDir dir;
  const ToolRun run = run_program(kOutcomes, "--gtest_list_tests", dir.path());
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("SkipsForAReason"), std::string::npos) << run.out;
}

}  // namespace
