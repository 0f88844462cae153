// Runs the built cvo-render tool.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <opencv2/imgcodecs.hpp>

#include "tests/support/cli_contract.hpp"

namespace {

namespace fs = std::filesystem;

int run(const std::string& args) {
  const std::string command = std::string(CVO_TOOLS_DIR) + "/cvo-render " + args + " >/dev/null 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string contents(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// Per-process names: several build trees may run this suite at once.
fs::path temp_path(const std::string& name) {
  return fs::path(testing::TempDir()) / (name + "_" + std::to_string(::getpid()));
}

int data_line_count(const fs::path& file) {
  std::ifstream in(file);
  int n = 0;
  for (std::string line; std::getline(in, line);) n += !line.empty() && line[0] != '#';
  return n;
}

TEST(CvoRenderCli, WritesADeterministicTumFolder) {
  const fs::path a = temp_path("cvo_render_cli_a"), b = temp_path("cvo_render_cli_b");
  fs::remove_all(a);
  fs::remove_all(b);
  ASSERT_EQ(run(a.string() + " --scene textured_wall --frames 3 --seed 4 --noise"), 0);
  ASSERT_EQ(run(b.string() + " --scene textured_wall --frames 3 --seed 4 --noise"), 0);
  for (const char* f : {"rgb.txt", "depth.txt", "groundtruth.txt", "camera.yaml"}) {
    ASSERT_TRUE(fs::is_regular_file(a / f)) << f;
    EXPECT_EQ(contents(a / f), contents(b / f)) << f;
  }
  EXPECT_EQ(data_line_count(a / "rgb.txt"), 3);
  EXPECT_EQ(data_line_count(a / "depth.txt"), 3);
  EXPECT_EQ(data_line_count(a / "groundtruth.txt"), 3);
  int images = 0;
  for (const auto& entry : fs::directory_iterator(a / "depth")) {
    ++images;
    const cv::Mat depth = cv::imread(entry.path().string(), cv::IMREAD_UNCHANGED);
    EXPECT_EQ(depth.type(), CV_16UC1);
    EXPECT_EQ(depth.size(), cv::Size(640, 480));
    EXPECT_EQ(contents(entry.path()), contents(b / "depth" / entry.path().filename()));
  }
  EXPECT_EQ(images, 3);
  for (const auto& entry : fs::directory_iterator(a / "rgb"))
    EXPECT_EQ(contents(entry.path()), contents(b / "rgb" / entry.path().filename()));
  fs::remove_all(a);
  fs::remove_all(b);
}

// The stress options: the same arguments give the same bytes (noise, blur and the auto-exposure
// loop all follow the seed), and the lists' header names them.
TEST(CvoRenderCli, SensorEffectsAreDeterministicAndNamedInTheLists) {
  const fs::path a = temp_path("cvo_render_cli_stress_a"), b = temp_path("cvo_render_cli_stress_b");
  const std::string args =
      " --scene white_room --path fast_rpy --frames 2 --seed 3 --sensor kinect --exposure 0.01 --auto-exposure"
      " --rolling-shutter 0.03";
  ASSERT_EQ(run(a.string() + args), 0);
  ASSERT_EQ(run(b.string() + args), 0);
  for (const auto& entry : fs::directory_iterator(a / "rgb"))
    EXPECT_EQ(contents(entry.path()), contents(b / "rgb" / entry.path().filename()));
  for (const auto& entry : fs::directory_iterator(a / "depth"))
    EXPECT_EQ(contents(entry.path()), contents(b / "depth" / entry.path().filename()));
  const std::string list = contents(a / "rgb.txt");
  EXPECT_NE(list.find("--scene white_room --path fast_rpy --seed 3 --rolling-shutter"), std::string::npos) << list;
  EXPECT_NE(list.find("--sensor kinect --exposure 0.010000 --auto-exposure"), std::string::npos) << list;
  fs::remove_all(a);
  fs::remove_all(b);
}

TEST(CvoRenderCli, BadArgumentsExitTwoIoErrorsExitOne) {
  const fs::path out = temp_path("cvo_render_cli_bad");
  EXPECT_EQ(run("--help"), 0);
  EXPECT_EQ(run(""), 2);
  EXPECT_EQ(run(out.string() + " --scene kitchen"), 2);
  EXPECT_EQ(run(out.string() + " --path spiral"), 2);
  EXPECT_EQ(run(out.string() + " --frames 0"), 2);
  EXPECT_EQ(run(out.string() + " --frames x"), 2);
  EXPECT_EQ(run(out.string() + " --seed -1"), 2);
  EXPECT_EQ(run(out.string() + " --frames"), 2);
  EXPECT_EQ(run(out.string() + " --bogus"), 2);
  EXPECT_EQ(run(out.string() + " --sensor kinect2"), 2);
  EXPECT_EQ(run(out.string() + " --exposure -0.01"), 2);
  EXPECT_EQ(run(out.string() + " other"), 2);
  EXPECT_FALSE(fs::exists(out));
  const fs::path file = temp_path("cvo_render_cli_file");
  std::ofstream(file) << "x";
  EXPECT_EQ(run((file / "sub").string() + " --frames 1"), 1);
  fs::remove(file);
}

TEST(CvoRenderCli, HelpListsEveryOptionAndAnUnknownOneExitsTwoNamingIt) {
  const fs::path scratch = temp_path("cvo_render_cli_contract");
  fs::create_directories(scratch);
  cvo::testing::expect_cli_contract("cvo-render", "",
                                    {"OUTDIR", "--scene", "--path", "--frames", "--seed", "--noise",
                                     "--rolling-shutter", "--sensor", "--exposure", "--auto-exposure"},
                                    scratch);
  fs::remove_all(scratch);
}

}  // namespace
