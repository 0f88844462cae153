// Runs the built cvo-run on temporary folders: the command-line contract others script against.
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <Eigen/Cholesky>

#include "libcvo/io/covariance_io.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/sim/sequence.hpp"
#include "tests/odometry/odometry_fixtures.hpp"
#include "tests/support/cli_contract.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::odometry {
namespace {

using cvo::testing::json_value;

namespace fs = std::filesystem;

using cvo::testing::run_tool;
using cvo::testing::slurp;
using cvo::testing::ToolRun;

std::string q(const fs::path& p) { return cvo::testing::quoted(p); }

ToolRun run_tool(const test::TempDir& dir, const std::string& args) { return run_tool("cvo-run", args, dir.path()); }

// Poses in a TUM trajectory file ('#' lines are comments).
std::size_t pose_lines(const fs::path& file) {
  std::ifstream in(file);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) n += !line.empty() && line.front() != '#';
  return n;
}

// A rendered TUM folder with exact ground truth: 40 frames (1.3 s, so there are RPE pairs 1 s
// apart), a half-size camera so the test renders in ~1 s; camera.yaml tells cvo-run the camera.
fs::path write_rendered_sequence(const test::TempDir& dir) {
  sim::SequenceOptions options;
  options.frames = 40;
  options.seed = 7;
  options.render = testing::fast_render();
  options.intrinsics = {262.5, 262.5, 159.25, 119.25, 320, 240, 5000.0};
  const fs::path seq = dir.path() / "seq";
  sim::write_sequence(seq, options);
  return seq;
}

TEST(CvoRunCli, RenderedSequenceEndToEnd) {
  const test::TempDir dir("cvo_run");
  const fs::path seq = write_rendered_sequence(dir);
  const fs::path traj = dir.path() / "traj.txt", png = dir.path() / "plot.png";

  const ToolRun r = run_tool(dir, q(seq) + " --out " + q(traj) + " --json --plot " + q(png));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(pose_lines(traj), 40u);
  EXPECT_EQ(io::read_tum_trajectory(traj).front().timestamp, 1000.0);
  ASSERT_EQ(r.out.front(), '{');
  EXPECT_EQ(r.out.substr(r.out.size() - 2), "}\n");
  EXPECT_EQ(json_value(r.out, "mode"), "\"cvo\"");
  EXPECT_EQ(json_value(r.out, "frames"), "40");
  EXPECT_EQ(json_value(r.out, "keyframes"), "0");
  EXPECT_EQ(json_value(r.out, "failed_frames"), "0");
  EXPECT_EQ(json_value(r.out, "failed_frame_list"), "[]");
  // Built with append(): GCC 12 warns falsely (-Wrestrict) on chained operator+ of short strings.
  EXPECT_EQ(json_value(r.out, "trajectory"), std::string("\"").append(traj.string()).append("\""));
  for (const char* key : {"ms_per_frame_median", "ms_per_frame_p90", "ms_per_frame_p99", "ms_per_frame_max",
                          "points_median", "iterations_median", "rpe_trans_m_s", "rpe_rot_deg_s"}) {
    const std::string v = json_value(r.out, key);
    EXPECT_TRUE(v != "<missing>" && v != "null") << key << ": " << v;
  }
  // Measured: ATE 1.2 mm, RPE 3.1 mm/s and 0.24 deg/s (exact depth, half-size images); a wrong
  // camera, timestamp or pose convention gives centimetres. Bounds about 2.5x.
  const double ate = std::stod(json_value(r.out, "ate_rmse_m"));
  std::printf("rendered, 40 frames at 320x240: ATE %.5f m, RPE %s m/s %s deg/s\n", ate,
              json_value(r.out, "rpe_trans_m_s").c_str(), json_value(r.out, "rpe_rot_deg_s").c_str());
  EXPECT_LT(ate, 0.003);
  EXPECT_LT(std::stod(json_value(r.out, "rpe_trans_m_s")), 0.008);
  EXPECT_LT(std::stod(json_value(r.out, "rpe_rot_deg_s")), 0.6);
  EXPECT_FALSE(cv::imread(png.string()).empty());
  // The human summary went to stderr.
  EXPECT_NE(r.err.find("ATE"), std::string::npos) << r.err;

  // Without --json the summary is on stdout; --max-frames limits the run.
  const ToolRun text = run_tool(dir, q(seq) + " --out " + q(traj) + " --max-frames 5");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("keyframes   0"), std::string::npos) << text.out;
  EXPECT_EQ(pose_lines(traj), 5u);
}

// Frames 0-7 of the real sample with frame 4's colour image overwritten by garbage: the frame is
// skipped and reported, the others are tracked. No ground truth in the copy: the ATE keys are null.
TEST(CvoRunCli, CorruptFrameIsReportedAndSkipped) {
  const test::TempDir dir("cvo_run");
  const fs::path src = CVO_TEST_DATA_DIR "/fr1_rpy_50", seq = dir.path() / "seq";
  fs::create_directories(seq);
  for (const char* index : {"rgb.txt", "depth.txt"}) {
    std::ifstream in(src / index);
    std::ofstream out(seq / index);
    fs::create_directories(seq / fs::path(index).stem());
    int frames = 0;
    for (std::string line; std::getline(in, line) && frames < 8;) {
      out << line << '\n';
      if (line.empty() || line.front() == '#') continue;
      const std::string file = line.substr(line.find(' ') + 1);
      fs::copy_file(src / file, seq / file);
      if (frames == 4 && std::string(index) == "rgb.txt") std::ofstream(seq / file, std::ios::trunc) << "garbage bytes";
      ++frames;
    }
  }
  const fs::path traj = dir.path() / "traj.txt";
  const ToolRun r = run_tool(dir, q(seq) + " --out " + q(traj) + " --json --set camera=tum_fr1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(pose_lines(traj), 7u);
  EXPECT_EQ(json_value(r.out, "frames"), "8");
  EXPECT_EQ(json_value(r.out, "poses"), "7");
  EXPECT_EQ(json_value(r.out, "failed_frames"), "1");
  EXPECT_NE(r.out.find("{\"index\": 4, "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"stage\": \"read\""), std::string::npos) << r.out;
  EXPECT_EQ(json_value(r.out, "ate_rmse_m"), "null");
  EXPECT_EQ(json_value(r.out, "groundtruth"), "null");
  EXPECT_NE(r.err.find("frame 4"), std::string::npos) << r.err;
  // --plot without ground truth is refused before the run.
  EXPECT_EQ(run_tool(dir, q(seq) + " --out " + q(traj) + " --set camera=tum_fr1 --plot x.png").exit_code, 2);
}

TEST(CvoRunCli, UsageErrorsExitTwo) {
  const test::TempDir dir("cvo_run");
  const std::string data = q(CVO_TEST_DATA_DIR "/fr1_rpy_50"), out = " --out " + q(dir.path() / "t.txt");
  for (const std::string& args : std::vector<std::string>{
           "", data, "--out x.txt", data + out + " --bogus", data + out + " --max-frames 0",
           data + out + " --max-frames ten", data + out + " --set cvo.no_such_key=1",
           data + out + " --set cvo.ell_init=-1", data + out + " --mode fast", data + " " + data + out}) {
    const ToolRun r = run_tool(dir, args);
    EXPECT_EQ(r.exit_code, 2) << "cvo-run " << args << "\n" << r.err;
    EXPECT_NE(r.err.find("usage:"), std::string::npos) << args;
  }
  const ToolRun help = run_tool(dir, "--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("usage: cvo-run SEQUENCE --out TRAJ.txt"), std::string::npos);
}

TEST(CvoRunCli, HelpListsEveryOptionAndAnUnknownOneExitsTwoNamingIt) {
  const test::TempDir dir("cvo_run");
  cvo::testing::expect_cli_contract("cvo-run", "",
                                    {"SEQUENCE", "--out", "--mode", "--max-frames", "--groundtruth", "--plot", "--json",
                                     "--config", "--set", "--vocabulary", "--covariance-out"},
                                    dir.path());
}

TEST(CvoRunCli, SetWithoutAnEqualsSignIsAUsageError) {
  const test::TempDir dir("cvo_run");
  cvo::testing::expect_set_needs_key_equals_value(
      "cvo-run", q(CVO_TEST_DATA_DIR "/fr1_rpy_50") + " --out " + q(dir.path() / "t.txt") + " --max-frames 2",
      dir.path());
}

// --set takes one value per occurrence: the folder after it is the SEQUENCE.
TEST(CvoRunCli, AFolderAfterSetIsTheSequence) {
  const test::TempDir dir("cvo_run");
  const ToolRun r = run_tool(dir, "--set camera=tum_fr1 " + q(CVO_TEST_DATA_DIR "/fr1_rpy_50") + " --out " +
                                      q(dir.path() / "t.txt") + " --max-frames 2 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json_value(r.out, "frames"), "2");
}

TEST(CvoRunCli, KeyframeModeEndToEnd) {
  // KF-CVO on a rendered orbit with exact ground truth: keyframes are made and reported, and the
  // trajectory is as good as frame-to-frame's (bound as in RenderedSequenceEndToEnd).
  const test::TempDir dir("cvo_run");
  const fs::path seq = write_rendered_sequence(dir);
  const fs::path traj = dir.path() / "traj.txt";
  const ToolRun r =
      run_tool(dir, q(seq) + " --out " + q(traj) + " --mode kf-cvo --json --set keyframe.translation_threshold_m=0.05");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json_value(r.out, "mode"), "\"kf-cvo\"");
  EXPECT_EQ(pose_lines(traj), 40u);
  EXPECT_GE(std::stoi(json_value(r.out, "keyframes")), 3);
  EXPECT_EQ(json_value(r.out, "failed_frames"), "0");
  EXPECT_LT(std::stod(json_value(r.out, "ate_rmse_m")), 0.003);
}

// --covariance-out: a line per frame with a measured motion (all but the first here), the colour
// stamp and 36 numbers of a symmetric positive-definite matrix; modes without one refuse it.
TEST(CvoRunCli, CovarianceOutWritesTheRelativePosesCovariancePerFrame) {
  const test::TempDir dir("cvo_run");
  const fs::path seq = write_rendered_sequence(dir);
  const fs::path traj = dir.path() / "traj.txt", cov = dir.path() / "traj.cov";
  const ToolRun r = run_tool(dir, q(seq) + " --out " + q(traj) + " --mode kf-cvo --covariance-out " + q(cov));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto trajectory = io::read_tum_trajectory(traj);
  const auto covariances = io::read_covariances(cov);
  ASSERT_EQ(covariances.size() + 1, trajectory.size());
  for (std::size_t k = 0; k < covariances.size(); ++k) {
    EXPECT_EQ(covariances[k].timestamp, trajectory[k + 1].timestamp);
    EXPECT_EQ(Eigen::LLT<core::Matrix6d>(covariances[k].covariance).info(), Eigen::Success) << "line " << k;
  }
  std::ifstream in(cov);
  std::string line;
  while (std::getline(in, line) && line.front() == '#') {
  }
  std::istringstream fields(line);
  std::size_t n = 0;
  for (std::string f; fields >> f;) ++n;
  EXPECT_EQ(n, 37u) << line;
  const ToolRun refused = run_tool(dir, q(seq) + " --out " + q(traj) + " --mode cvo --covariance-out " + q(cov));
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("--covariance-out"), std::string::npos) << refused.err;
}

// With honest edge information the back end never makes the odometry worse: a rendered sequence of
// fast turns with Kinect-like depth noise.
TEST(CvoRunCli, SlamIsNoWorseThanItsOwnOdometryOnANoisyRenderedSequence) {
  const test::TempDir dir("cvo_run");
  sim::SequenceOptions options;
  options.path = sim::PathKind::rpy;
  options.frames = 90;
  options.seed = 3;
  options.noise.enabled = true;
  options.render = testing::fast_render();
  const fs::path seq = dir.path() / "rpy";
  sim::write_sequence(seq, options);
  const ToolRun r = run_tool(dir, q(seq) + " --out " + q(dir.path() / "traj.txt") + " --mode slam --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double ate = std::stod(json_value(r.out, "ate_rmse_m"));
  const double odometry = std::stod(json_value(r.out, "ate_rmse_m_odometry"));
  std::printf("rendered rpy with noise: slam ATE %.5f m, its odometry's %.5f m\n", ate, odometry);
  EXPECT_LE(ate, odometry);
}

TEST(CvoRunCli, InputErrorsExitOneAndNameTheFile) {
  const test::TempDir dir("cvo_run");
  const fs::path missing = dir.path() / "no_such_sequence";
  ToolRun r = run_tool(dir, q(missing) + " --out " + q(dir.path() / "t.txt"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(missing.string()), std::string::npos) << r.err;

  const std::string data = q(CVO_TEST_DATA_DIR "/fr1_rpy_50");
  const fs::path gt = dir.path() / "no_gt.txt";
  r = run_tool(dir, data + " --out " + q(dir.path() / "t.txt") + " --groundtruth " + q(gt));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(gt.string()), std::string::npos) << r.err;

  const fs::path config = dir.path() / "no_config.yaml";
  r = run_tool(dir, data + " --out " + q(dir.path() / "t.txt") + " --config " + q(config));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(config.string()), std::string::npos) << r.err;

  const fs::path unwritable = dir.path() / "no_dir" / "t.txt";
  r = run_tool(dir, data + " --out " + q(unwritable));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(unwritable.string()), std::string::npos) << r.err;
}

}  // namespace
}  // namespace cvo::odometry
