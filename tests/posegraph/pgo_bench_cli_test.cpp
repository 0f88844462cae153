// Runs the built pgo-bench the way a script would: both solvers on one g2o file, --json keys.
#include <filesystem>
#include <regex>
#include <string>

#include <gtest/gtest.h>

#include "tests/posegraph/indefinite_graph.hpp"
#include "tests/posegraph/json_syntax.hpp"
#include "tests/support/cli_contract.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::posegraph {
namespace {

namespace fs = std::filesystem;
using cvo::testing::json_value;
using cvo::testing::JsonSyntax;
using cvo::testing::quoted;
using cvo::testing::run_tool;

double number_after(const std::string& json, const std::string& solver, const std::string& key) {
  std::smatch m;
  const std::regex re("\"" + solver + "\": \\{[^}]*\"" + key + "\": ([-0-9.eE+]+)");
  if (!std::regex_search(json, m, re)) return -1;
  return std::stod(m[1]);
}

TEST(PgoBenchCli, BothSolversReachTheSameCostOnTinyGrid) {
  const fs::path file = fs::path(CVO_SHARED_DATA_DIR) / "posegraph" / "tinyGrid3D.g2o";
  if (!fs::exists(file)) GTEST_SKIP() << "shared data absent: " << file;
  const test::TempDir dir("pgo_bench");
  const auto r = run_tool("pgo-bench", quoted(file) + " --json", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* solver : {"cvo", "ceres"}) {
    EXPECT_GT(number_after(r.out, solver, "iterations"), 0) << solver << "\n" << r.out;
    EXPECT_GT(number_after(r.out, solver, "factorizations"), 0) << solver << "\n" << r.out;
    EXPECT_GE(number_after(r.out, solver, "seconds"), 0) << solver;
  }
  const double ours = number_after(r.out, "cvo", "final_cost"), ceres = number_after(r.out, "ceres", "final_cost");
  EXPECT_LT(ours, number_after(r.out, "cvo", "initial_cost"));
  EXPECT_NEAR(ours, ceres, 1e-3 * ceres);  // the issue's target: equal final cost within 0.1 %
}

// The check the next test relies on: foreign text in the middle of the object, or after it, is
// caught.
TEST(PgoBenchCli, JsonSyntaxCheckCatchesForeignText) {
  const std::string good = R"({"a": [1, -0.5e-3, true, null], "b": {"c": "x\"y\u00e9"}})";
  EXPECT_TRUE(JsonSyntax::valid(good + "\n"));
  EXPECT_FALSE(JsonSyntax::valid(R"({"a": [1, CHOLMOD error: matrix not positive definite. 2]})"));
  EXPECT_FALSE(JsonSyntax::valid(good + "\nCHOLMOD warning: matrix not positive definite.\n"));
  EXPECT_FALSE(JsonSyntax::valid(R"({"a": 01})"));
  EXPECT_FALSE(JsonSyntax::valid(R"({"a": nan})"));
  EXPECT_FALSE(JsonSyntax::valid(R"({"a": 1,})"));
}

// indefinite_graph.hpp: used as given, its cost has a negative minimum, which both solvers
// reported as converged; repaired, both reach the truth at a cost of ~0.
TEST(PgoBenchCli, IndefiniteInformationIsRepairedWithAWarningAndJsonStaysClean) {
  const test::TempDir dir("pgo_bench");
  const fs::path file = dir.write("indefinite.g2o", test_graphs::kIndefiniteGraph);
  const auto r = run_tool("pgo-bench", quoted(file) + " --json", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(JsonSyntax::valid(r.out)) << r.out;
  EXPECT_EQ(r.out.find("CHOLMOD"), std::string::npos) << r.out;
  EXPECT_EQ(json_value(r.out, "repaired_information"), std::to_string(test_graphs::kIndefiniteEdges)) << r.out;
  const std::string where = file.string() + ":" + std::to_string(test_graphs::kFirstIndefiniteLine) + ": warning: ";
  const auto at = r.err.find(where);
  EXPECT_NE(at, std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(where, at + 1), std::string::npos) << "one warning per file:\n" << r.err;
  EXPECT_NE(r.err.find("2 of 5 edges"), std::string::npos) << r.err;
  for (const char* solver : {"cvo", "ceres"}) {
    const double final_cost = number_after(r.out, solver, "final_cost");
    EXPECT_GE(final_cost, 0.0) << solver << "\n" << r.out;
    EXPECT_LT(final_cost, 1e-6) << solver << "\n" << r.out;
    EXPECT_GE(number_after(r.out, solver, "solver_cost"), 0.0) << solver << "\n" << r.out;
  }
}

TEST(PgoBenchCli, BadInputAndArguments) {
  const test::TempDir dir("pgo_bench");
  const fs::path bad = dir.path() / "bad.g2o";
  dir.write("bad.g2o", "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nEDGE_SE3:QUAT 0 oops\n");
  auto r = run_tool("pgo-bench", quoted(bad), dir.path());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("bad.g2o:2"), std::string::npos) << r.err;
  r = run_tool("pgo-bench", "--no-such-option", dir.path());
  EXPECT_EQ(r.exit_code, 2);
}

TEST(PgoBenchCli, HelpListsEveryOptionAndAnUnknownOneExitsTwoNamingIt) {
  const test::TempDir dir("pgo_bench");
  cvo::testing::expect_cli_contract("pgo-bench", "", {"FILE.g2o", "--json", "--max-iterations", "--robust", "--repeat"},
                                    dir.path());
}

// An iteration cap is a count in decimal: not negative, hexadecimal or fractional, nor 0.
TEST(PgoBenchCli, MaxIterationsTakesOnlyAPositiveDecimalCount) {
  const test::TempDir dir("pgo_bench");
  const fs::path file = dir.write("indefinite.g2o", test_graphs::kIndefiniteGraph);
  for (const char* value : {"0", "-1", "0x10", "1.5", "ten", "1000001"}) {
    const auto r = run_tool("pgo-bench", quoted(file) + " --max-iterations " + value, dir.path());
    EXPECT_EQ(r.exit_code, 2) << value << ": " << r.err;
    EXPECT_NE(r.err.find("--max-iterations"), std::string::npos) << value << ": " << r.err;
  }
  const auto r = run_tool("pgo-bench", quoted(file) + " --json --max-iterations 010", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json_value(r.out, "max_iterations"), "10") << "decimal, not octal";
  EXPECT_EQ(json_value(r.out, "robust"), "false");
  EXPECT_EQ(json_value(r.out, "nodes"), "4") << "an integer, not 4.0\n" << r.out;
  EXPECT_EQ(json_value(r.out, "edges"), std::to_string(test_graphs::kEdges)) << r.out;
}

// --repeat N solves N times and reports the median time; like --max-iterations, a decimal count.
TEST(PgoBenchCli, RepeatTakesAPositiveCountAndKeepsTheResult) {
  const test::TempDir dir("pgo_bench");
  const fs::path file = dir.write("indefinite.g2o", test_graphs::kIndefiniteGraph);
  for (const char* value : {"0", "-2", "x", "1001"}) {
    const auto r = run_tool("pgo-bench", quoted(file) + " --repeat " + value, dir.path());
    EXPECT_EQ(r.exit_code, 2) << value << ": " << r.err;
    EXPECT_NE(r.err.find("--repeat"), std::string::npos) << value << ": " << r.err;
  }
  const auto once = run_tool("pgo-bench", quoted(file) + " --json", dir.path());
  const auto thrice = run_tool("pgo-bench", quoted(file) + " --json --repeat 3", dir.path());
  ASSERT_EQ(thrice.exit_code, 0) << thrice.err;
  EXPECT_TRUE(JsonSyntax::valid(thrice.out)) << thrice.out;
  EXPECT_EQ(json_value(thrice.out, "repeat"), "3") << thrice.out;
  EXPECT_EQ(json_value(once.out, "repeat"), "1") << once.out;
  for (const char* solver : {"cvo", "ceres"}) {
    EXPECT_EQ(number_after(thrice.out, solver, "final_cost"), number_after(once.out, solver, "final_cost")) << solver;
    EXPECT_EQ(number_after(thrice.out, solver, "iterations"), number_after(once.out, solver, "iterations")) << solver;
  }
}

}  // namespace
}  // namespace cvo::posegraph
