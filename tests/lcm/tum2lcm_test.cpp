// tum2lcm: a TUM folder becomes an LCM log of CVO_RGBD frames equal to the dataset's, and
// --to-tum brings it back pixel-exact for the lossless encodings.
#include <lcm/lcm-cpp.hpp>

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"
#include "support/cli_contract.hpp"
#include "support/run_tool.hpp"
#include "support/temp_dir.hpp"

namespace cvo::lcm {
namespace {

namespace fs = std::filesystem;
using testing::quoted;
using testing::run_tool;

const fs::path kDataset = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0;
}

struct LogEvent {
  std::int64_t timestamp;
  std::string channel;
  core::RgbdFrame frame;
  std::int64_t utime;
};

std::vector<LogEvent> read_log(const fs::path& log) {
  ::lcm::LogFile in(log.string(), "r");
  EXPECT_TRUE(in.good());
  std::vector<LogEvent> events;
  while (const ::lcm::LogEvent* e = in.readNextEvent()) {
    std::string error;
    const auto m = decode<cvo_lcm::rgbd_frame_t>(e->data, e->datalen, &error);
    EXPECT_TRUE(m) << error;
    if (!m) continue;
    const auto frame = from_message(*m, &error);
    EXPECT_TRUE(frame) << error;
    events.push_back({e->timestamp, e->channel, frame.value_or(core::RgbdFrame{}), m->utime});
  }
  return events;
}

TEST(Tum2Lcm, LogHoldsTheDatasetFramesInOrder) {
  test::TempDir dir("tum2lcm");
  const auto log = dir.path() / "fr1.lcmlog";
  const auto run = run_tool("tum2lcm", quoted(kDataset) + " " + quoted(log) + " --max-frames 5", dir.path());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("wrote 5 frames"), std::string::npos) << run.out;

  const auto events = read_log(log);
  ASSERT_EQ(events.size(), 5u);
  const auto tum = io::TumSequence::open(kDataset);
  for (std::size_t i = 0; i < events.size(); ++i) {
    SCOPED_TRACE("frame " + std::to_string(i));
    const auto expected = tum.read(i);
    EXPECT_EQ(events[i].channel, "CVO_RGBD");
    EXPECT_EQ(events[i].timestamp, events[i].utime) << "event time is the frame's time";
    EXPECT_EQ(events[i].frame.index, i);
    EXPECT_EQ(events[i].frame.timestamp, expected.timestamp);
    EXPECT_EQ(events[i].frame.depth_timestamp, expected.depth_timestamp);
    EXPECT_EQ(events[i].frame.intrinsics.fx, expected.intrinsics.fx);
    EXPECT_TRUE(identical(events[i].frame.bgr, expected.bgr));
    EXPECT_TRUE(identical(events[i].frame.depth, expected.depth));
    if (i > 0) {
      EXPECT_GT(events[i].timestamp, events[i - 1].timestamp);
    }
  }
}

TEST(Tum2Lcm, ChannelAndJpegOptions) {
  test::TempDir dir("tum2lcm");
  const auto log = dir.path() / "jpeg.lcmlog";
  const auto run = run_tool(
      "tum2lcm", quoted(kDataset) + " " + quoted(log) + " --max-frames 2 --colour jpeg --depth raw --channel CAM_FRONT",
      dir.path());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto events = read_log(log);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].channel, "CAM_FRONT");
  const auto expected = io::TumSequence::open(kDataset).read(0);
  EXPECT_TRUE(identical(events[0].frame.depth, expected.depth));
  EXPECT_LT(cv::norm(events[0].frame.bgr, expected.bgr, cv::NORM_L1) / (expected.bgr.total() * 3.0), 4.0);
}

TEST(Tum2Lcm, ToTumRoundTripIsExactForLosslessEncodings) {
  for (const std::string encoding : {"png", "raw"}) {
    SCOPED_TRACE(encoding);
    test::TempDir dir("tum2lcm");
    const auto log = dir.path() / "in.lcmlog";
    const auto out = dir.path() / "back";
    auto run =
        run_tool("tum2lcm",
                 quoted(kDataset) + " " + quoted(log) + " --max-frames 5 --colour " + encoding + " --depth " + encoding,
                 dir.path());
    ASSERT_EQ(run.exit_code, 0) << run.err;
    run = run_tool("tum2lcm", "--to-tum " + quoted(log) + " " + quoted(out), dir.path());
    ASSERT_EQ(run.exit_code, 0) << run.err;

    const auto original = io::TumSequence::open(kDataset);
    const auto back = io::TumSequence::open(out);  // its own camera.yaml
    ASSERT_EQ(back.size(), 5u);
    EXPECT_EQ(back.intrinsics().fx, original.intrinsics().fx);
    EXPECT_EQ(back.intrinsics().depth_scale, original.intrinsics().depth_scale);
    EXPECT_TRUE(original.intrinsics().has_distortion());  // tum_fr1, through CVO_RGBD and camera.yaml
    EXPECT_EQ(back.intrinsics().distortion, original.intrinsics().distortion);
    for (std::size_t i = 0; i < back.size(); ++i) {
      const auto a = original.read(i), b = back.read(i);
      EXPECT_EQ(a.timestamp, b.timestamp);
      EXPECT_EQ(a.depth_timestamp, b.depth_timestamp);
      EXPECT_TRUE(identical(a.bgr, b.bgr)) << i;
      EXPECT_TRUE(identical(a.depth, b.depth)) << i;
    }
  }
}

TEST(Tum2Lcm, HelpListsEveryOptionAndAnUnknownOneExitsTwoNamingIt) {
  test::TempDir dir("tum2lcm");
  testing::expect_cli_contract(
      "tum2lcm", "",
      {"INPUT", "OUTPUT", "--to-tum", "--colour", "--color", "--depth", "--jpeg-quality", "--channel", "--max-frames"},
      dir.path());
}

TEST(Tum2Lcm, ExitCodes) {
  test::TempDir dir("tum2lcm");
  auto run = run_tool("tum2lcm", "", dir.path());
  EXPECT_EQ(run.exit_code, 2);
  run = run_tool("tum2lcm", quoted(kDataset) + " x.lcmlog --colour webp", dir.path());
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--colour"), std::string::npos) << run.err;
  run = run_tool("tum2lcm", "--help", dir.path());
  EXPECT_EQ(run.exit_code, 0);

  const auto missing = dir.path() / "no_such_dataset";
  run = run_tool("tum2lcm", quoted(missing) + " " + quoted(dir.path() / "x.lcmlog"), dir.path());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("no_such_dataset"), std::string::npos) << run.err;

  const auto not_a_log = dir.write("garbage.lcmlog", "this is not an LCM log");
  run = run_tool("tum2lcm", "--to-tum " + quoted(not_a_log) + " " + quoted(dir.path() / "out"), dir.path());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("garbage.lcmlog"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace cvo::lcm
