#include "libcvo/sim/sequence.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <unistd.h>
#include <opencv2/imgcodecs.hpp>

#include "libcvo/io/input_error.hpp"
#include "libcvo/io/trajectory_io.hpp"

namespace cvo::sim {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> data_lines(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') lines.push_back(line);
  return lines;
}

// Per-process names: several build trees may run this suite at once.
fs::path temp_path(const std::string& name) {
  return fs::path(testing::TempDir()) / (name + "_" + std::to_string(::getpid()));
}

SequenceOptions small_options() {
  SequenceOptions options;
  options.intrinsics = {131.25, 131.25, 79.5, 59.5, 160, 120, 5000.0};
  options.frames = 4;
  options.seed = 9;
  return options;
}

TEST(RenderSequence, WritesATumFolderWithExactGroundTruth) {
  const fs::path dir = temp_path("sim_sequence_test");
  fs::remove_all(dir);
  const SequenceSummary summary = write_sequence(dir, small_options());
  EXPECT_EQ(summary.frames, 4u);
  EXPECT_NEAR(summary.duration_s, 0.1, 1e-6);
  EXPECT_GT(summary.valid_depth_fraction, 0.95);

  const auto rgb = data_lines(dir / "rgb.txt"), depth = data_lines(dir / "depth.txt");
  ASSERT_EQ(rgb.size(), 4u);
  ASSERT_EQ(depth.size(), 4u);
  EXPECT_EQ(rgb[0], "1000.000000 rgb/1000.000000.png");
  EXPECT_EQ(depth[1], "1000.033333 depth/1000.033333.png");
  const auto truth = io::read_tum_trajectory(dir / "groundtruth.txt");
  ASSERT_EQ(truth.size(), 4u);
  EXPECT_DOUBLE_EQ(truth[3].timestamp, 1000.1);
  EXPECT_TRUE(truth[2].pose.matrix().isApprox(path_pose(PathKind::orbit, truth[2].timestamp - 1000.0).matrix(), 1e-8));

  const cv::Mat colour = cv::imread((dir / "rgb" / "1000.000000.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat d = cv::imread((dir / "depth" / "1000.066667.png").string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(colour.type(), CV_8UC3);
  EXPECT_EQ(d.type(), CV_16UC1);
  EXPECT_EQ(d.size(), cv::Size(160, 120));

  std::ifstream yaml(dir / "camera.yaml");
  std::stringstream text;
  text << yaml.rdbuf();
  for (const char* key : {"fx: 131.25\n", "fy: 131.25\n", "cx: 79.5\n", "cy: 59.5\n", "width: 160\n", "height: 120\n",
                          "depth_scale: 5000\n"})
    EXPECT_NE(text.str().find(key), std::string::npos) << key;
  fs::remove_all(dir);
}

TEST(RenderSequence, UnwritableFolderIsAClearError) {
  const fs::path file = temp_path("sim_sequence_not_a_dir");
  std::ofstream(file) << "x";
  try {
    write_sequence(file / "out", small_options());
    FAIL() << "no error";
  } catch (const io::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sim_sequence_not_a_dir"), std::string::npos) << e.what();
  }
  fs::remove(file);
}

}  // namespace
}  // namespace cvo::sim
