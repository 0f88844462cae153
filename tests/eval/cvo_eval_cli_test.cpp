// Runs the built cvo-eval on temporary files: the command-line contract others script against.
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "eval/test_trajectories.hpp"
#include "libcvo/io/covariance_io.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "tests/support/cli_contract.hpp"
#include "tests/support/run_tool.hpp"

namespace cvo::eval {
namespace {

using cvo::testing::json_value;

namespace fs = std::filesystem;
using cvo::testing::quoted;
using cvo::testing::run_tool;
using cvo::testing::slurp;
using cvo::testing::ToolRun;
using testing::kStep;
using testing::make;

// A fresh folder per test: ctest runs the tests of this file in parallel processes.
class CvoEvalCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("cvo_eval_cli_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    gt_ = dir_ / "gt.txt";
    est_ = dir_ / "est.txt";
    // Ground truth along x at 1 m/s; the estimate drifts by v = 5 cm/s (see the library tests).
    io::write_tum_trajectory(gt_, make(41, [](double t) { return core::SE3::from_translation({t, 0, 0}); }));
    io::write_tum_trajectory(est_, make(41, [](double t) { return core::SE3::from_translation({1.05 * t, 0, 0}); }));
  }
  void TearDown() override { fs::remove_all(dir_); }

  ToolRun run(const std::string& args) const { return run_tool("cvo-eval", args, dir_); }
  static std::string q(const fs::path& p) { return quoted(p); }

  fs::path dir_, gt_, est_;
};

TEST_F(CvoEvalCli, JsonHasTheContractKeysAndTheRightNumbers) {
  const ToolRun r = run(q(gt_) + " " + q(est_) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.front(), '{');
  EXPECT_EQ(r.out.substr(r.out.size() - 2), "}\n");
  EXPECT_EQ(r.out.find("nan"), std::string::npos);
  EXPECT_EQ(json_value(r.out, "pairs"), "41");
  EXPECT_EQ(json_value(r.out, "rpe_pairs"), "32");
  // ATE of a 5 % stretch over 41 stamps 1/8 s apart: 0.05 * 0.125 * sqrt((41^2 - 1) / 12).
  EXPECT_NEAR(std::stod(json_value(r.out, "ate_rmse_m")), 0.05 * kStep * std::sqrt((41.0 * 41 - 1) / 12), 1e-12);
  EXPECT_NEAR(std::stod(json_value(r.out, "ate_max_m")), 0.05 * kStep * 20, 1e-12);
  EXPECT_NEAR(std::stod(json_value(r.out, "rpe_trans_m_s")), 0.05, 1e-12);
  EXPECT_NEAR(std::stod(json_value(r.out, "rpe_rot_deg_s")), 0.0, 1e-5);
  for (const char* key : {"ate_mean_m", "ate_median_m", "rpe_trans_mean_m_s", "rpe_rot_mean_deg_s", "rpe_delta_s"})
    EXPECT_NE(json_value(r.out, key), "<missing>") << key;
  EXPECT_EQ(json_value(r.out, "groundtruth"), std::string("\"").append(gt_.string()).append("\""));
  EXPECT_EQ(json_value(r.out, "estimate"), std::string("\"").append(est_.string()).append("\""));
}

// The estimate's relative poses err by 5 % of 12.5 cm along x; a covariance of exactly that
// standard deviation on every axis makes every pair's NEES 1.
TEST_F(CvoEvalCli, CovarianceAddsTheNeesOfTheRelativePoses) {
  const fs::path cov = dir_ / "est.cov";
  std::vector<io::StampedCovariance> covariances;
  const double sigma = 0.05 * kStep;
  for (int k = 1; k <= 40; ++k) covariances.push_back({k * kStep, sigma * sigma * core::Matrix6d::Identity()});
  io::write_covariances(cov, covariances);
  const ToolRun r = run(q(gt_) + " " + q(est_) + " --covariance " + q(cov) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json_value(r.out, "nees_pairs"), "40");
  EXPECT_NEAR(std::stod(json_value(r.out, "nees_mean")), 1.0, 1e-6);
  EXPECT_NEAR(std::stod(json_value(r.out, "nees_median")), 1.0, 1e-6);
  EXPECT_NEAR(std::stod(json_value(r.out, "nees_translation_mean")), 1.0, 1e-6);
  EXPECT_NEAR(std::stod(json_value(r.out, "nees_rotation_mean")), 0.0, 1e-6);
  const ToolRun table = run(q(gt_) + " " + q(est_) + " --covariance " + q(cov));
  EXPECT_NE(table.out.find("NEES"), std::string::npos) << table.out;
  // Without --covariance the keys are absent; a bad file is exit 1 naming it.
  EXPECT_EQ(json_value(run(q(gt_) + " " + q(est_) + " --json").out, "nees_mean"), "<missing>");
  std::ofstream(dir_ / "bad.cov") << "1.0 2.0\n";
  const ToolRun bad = run(q(gt_) + " " + q(est_) + " --covariance " + q(dir_ / "bad.cov"));
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("bad.cov"), std::string::npos) << bad.err;
}

TEST_F(CvoEvalCli, TableIsTheDefaultAndOptionsApply) {
  const ToolRun r = run(q(gt_) + " " + q(est_));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("ATE [m]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("RPE trans [m/s]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("RPE rot [deg/s]"), std::string::npos) << r.out;
  const ToolRun two = run(q(gt_) + " " + q(est_) + " --json --delta 2 --max-dt 0.01");
  ASSERT_EQ(two.exit_code, 0) << two.err;
  EXPECT_NEAR(std::stod(json_value(two.out, "rpe_trans_m_s")), 0.1, 1e-12);
  EXPECT_EQ(json_value(two.out, "max_dt_s"), "0.01");
}

TEST_F(CvoEvalCli, PlotWritesAReadablePng) {
  const fs::path png = dir_ / "eval.png";
  const ToolRun r = run(q(gt_) + " " + q(est_) + " --plot " + q(png) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const cv::Mat img = cv::imread(png.string());
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 1200);
  EXPECT_EQ(img.rows, 600);
  EXPECT_EQ(run(q(gt_) + " " + q(est_) + " --plot /nonexistent/dir/x.png").exit_code, 1);
}

TEST_F(CvoEvalCli, BadInputExitsOneNamingTheFile) {
  const ToolRun missing = run(q(gt_) + " " + q(dir_ / "nope.txt"));
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("nope.txt"), std::string::npos) << missing.err;

  std::ofstream(dir_ / "bad.txt") << "# header\n1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n";
  const ToolRun bad = run(q(dir_ / "bad.txt") + " " + q(est_));
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("bad.txt:3"), std::string::npos) << bad.err;

  std::ofstream(dir_ / "far.txt") << "1000 0 0 0 0 0 0 1\n1001 0 0 0 0 0 0 1\n1002 0 0 0 0 0 0 1\n";
  const ToolRun far = run(q(gt_) + " " + q(dir_ / "far.txt"));
  EXPECT_EQ(far.exit_code, 1);
  EXPECT_NE(far.err.find("at least 3"), std::string::npos) << far.err;

  std::ofstream(dir_ / "empty.txt") << "# nothing\n";
  EXPECT_EQ(run(q(dir_ / "empty.txt") + " " + q(est_)).exit_code, 1);
}

TEST_F(CvoEvalCli, HelpListsEveryOptionAndAnUnknownOneExitsTwoNamingIt) {
  cvo::testing::expect_cli_contract(
      "cvo-eval", "",
      {"GROUNDTRUTH", "ESTIMATE", "--json", "--plot", "--covariance", "--max-dt", "--delta", "--offset"}, dir_);
}

TEST_F(CvoEvalCli, BadArgumentsExitTwo) {
  for (const std::string& args : {std::string(""), q(gt_), q(gt_) + " " + q(est_) + " " + q(est_),
                                  q(gt_) + " " + q(est_) + " --frobnicate", q(gt_) + " " + q(est_) + " --plot",
                                  q(gt_) + " " + q(est_) + " --delta abc", q(gt_) + " " + q(est_) + " --max-dt -1"}) {
    const ToolRun r = run(args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_NE(r.err.find("usage:"), std::string::npos) << args;
    EXPECT_TRUE(r.out.empty()) << args;
  }
  const ToolRun help = run("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("usage:"), std::string::npos);
}

TEST_F(CvoEvalCli, ShortEstimateHasAteButNullRpe) {
  const fs::path short_est = dir_ / "short.txt";
  io::write_tum_trajectory(short_est, make(5, [](double t) { return core::SE3::from_translation({t, 0, 0}); }));
  const ToolRun r = run(q(gt_) + " " + q(short_est) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json_value(r.out, "pairs"), "5");
  EXPECT_EQ(json_value(r.out, "rpe_trans_m_s"), "null");
  EXPECT_EQ(json_value(r.out, "rpe_pairs"), "0");
  EXPECT_NE(r.err.find("warning"), std::string::npos) << r.err;
}

TEST_F(CvoEvalCli, FileNamesAreEscapedInJson) {
  const fs::path odd = dir_ / "we\"ird\\name.txt";
  fs::copy_file(est_, odd);
  const ToolRun r = run(q(gt_) + " " + q(odd) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("we\\\"ird\\\\name.txt\""), std::string::npos) << r.out;
}

TEST_F(CvoEvalCli, RealGroundTruthAgainstItself) {
  const fs::path file = fs::path(CVO_SHARED_DATA_DIR) / "tum/fr1_rpy/groundtruth.txt";
  if (!fs::exists(file)) GTEST_SKIP() << "shared data absent: " << file;
  const ToolRun r = run(q(file) + " " + q(file) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json_value(r.out, "pairs"), std::to_string(io::read_tum_trajectory(file).size()));
  EXPECT_LT(std::stod(json_value(r.out, "ate_rmse_m")), 1e-9);
  EXPECT_LT(std::stod(json_value(r.out, "rpe_trans_m_s")), 1e-9);
}

}  // namespace
}  // namespace cvo::eval
