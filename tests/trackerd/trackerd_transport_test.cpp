// One tracker whatever the transport: cvo-trackerd on the embedded clip read as a TUM folder
// (tum:) and as tum2lcm's CVO_RGBD recording of it (lcm:, lossless PNG images) tracks the same
// frames with the same camera (its rolling-shutter readout included), so it gives the same poses.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/core/se3.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/lcm_log.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";

// cvo-trackerd --deterministic on `source` to its end; what it published.
cvo::testing::PublishedLog track(const fs::path& dir, const std::string& name, const std::string& source) {
  const auto out = dir / (name + ".lcmlog");
  const auto err = dir / (name + ".txt");
  cvo::testing::DaemonProcess d(
      fs::path(CVO_TOOLS_DIR) / "cvo-trackerd",
      {"--source", source, "--exit-on-eof", "--deterministic", "--lcm-url", "file://" + out.string() + "?mode=w",
       "--set", "trackerd.realtime_priority=0", "--set", "trackerd.lock_memory=false", "--set", "trackerd.paced=false"},
      err);
  const auto code = d.wait_for(120s);
  EXPECT_TRUE(code) << name << " still running";
  EXPECT_EQ(code.value_or(-9), 0) << cvo::testing::slurp(err);
  return cvo::testing::read_published(out);
}

core::SE3 pose_of(const cvo_lcm::pose3d_t& p) { return *lcm::from_message(p, nullptr); }

TEST(TrackerdTransport, TheSameFramesThroughTumAndLcmGiveTheSamePoses) {
  cvo::test::TempDir dir;
  const auto recording = dir.path() / "clip.lcmlog";
  const auto r = cvo::testing::run_tool(
      "tum2lcm", cvo::testing::quoted(kClip) + " " + cvo::testing::quoted(recording) + " --colour png --depth png",
      dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;

  const auto tum = track(dir.path(), "tum", "tum:" + kClip.string());
  const auto lcm = track(dir.path(), "lcm", "lcm:file://" + recording.string() + "?speed=0");
  ASSERT_EQ(tum.poses.size(), 50u);
  ASSERT_EQ(lcm.poses.size(), tum.poses.size());
  double worst_m = 0, worst_rad = 0;
  for (std::size_t i = 0; i < tum.poses.size(); ++i) {
    const auto& a = tum.poses[i];
    const auto& b = lcm.poses[i];
    EXPECT_EQ(a.frame_index, b.frame_index);
    EXPECT_EQ(a.utime, b.utime) << "frame " << i;
    EXPECT_EQ(a.status, b.status) << "frame " << i;
    EXPECT_EQ(a.is_keyframe, b.is_keyframe) << "frame " << i;
    const core::SE3 difference = pose_of(a.odom_pose).inverse() * pose_of(b.odom_pose);
    const double metres = difference.translation().norm(), radians = core::so3_log(difference.rotation()).norm();
    EXPECT_LE(metres, 1e-6) << "frame " << i;
    EXPECT_LE(radians, 1e-6) << "frame " << i;
    worst_m = std::max(worst_m, metres);
    worst_rad = std::max(worst_rad, radians);
  }
  std::cout << "largest difference: " << worst_m << " m, " << worst_rad << " rad\n";

  // The keyframes carry the camera as the TUM folder gives it, its readout too.
  ASSERT_EQ(lcm.keyframes.size(), tum.keyframes.size());
  for (std::size_t i = 0; i < tum.keyframes.size(); ++i) {
    EXPECT_GT(tum.keyframes[i].readout_s, 0) << "fr1 is a Kinect, a rolling shutter";
    EXPECT_EQ(lcm.keyframes[i].readout_s, tum.keyframes[i].readout_s);
  }
}

}  // namespace
}  // namespace cvo::daemon
