// cvo-trackerd --source v4l2:COLOUR,DEPTH over an emulated camera pair playing
// tests/data/fr1_rpy_50: the real executable, the real v4l2: driver and ReconnectingSource, the
// emulator in its LD_PRELOAD. The camera is lossless (it waits for free buffers instead of
// dropping frames) and leaves at the end of the clip, so every run tracks exactly the clip's 50
// frames, whatever the machine's speed; the departure tells the test the clip was read.
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/eval/ate.hpp"
#include "libcvo/eval/rpe.hpp"
#include "libcvo/io/intrinsics_file.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "tests/drivers/v4l2_emulator/emulated.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/lcm_log.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/slowdown.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::drivers {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::DaemonProcess;

const fs::path kTrackerd = fs::path(CVO_TOOLS_DIR) / "cvo-trackerd";
const std::string kNodes = "/dev/video110,/dev/video111";

// The clip's calibration with the emulated camera's depth unit (millimetres): what a user writes
// for a V4L2 camera (trackerd's `camera` key).
fs::path camera_file(const fs::path& dir) {
  auto k = *core::camera_preset("tum_fr1");
  k.depth_scale = 1000;
  const auto file = dir / "camera.yaml";
  std::ofstream(file) << io::format_intrinsics_yaml(k, "fr1 as the emulated V4L2 camera sends it");
  return file;
}

struct Run {
  int exit_code = -2;
  std::string err;
  cvo::testing::PublishedLog log;
};

// cvo-trackerd on the emulated camera described by `camera` (extra keys), until the camera has
// left `departures` times; then SIGTERM, as systemd stops it.
Run track(const std::string& camera, int departures) {
  cvo::test::TempDir dir;
  const auto out = dir.path() / "out.lcmlog", err = dir.path() / "stderr.txt";
  const std::string emulated = "colour=" + kNodes.substr(0, kNodes.find(',')) +
                               ",depth=" + kNodes.substr(kNodes.find(',') + 1) +
                               ",tum=" + cvo::testing::kEmulatedClip.string() +
                               ",colour_size=640x480,depth_size=640x480,lossless=1,at_end=unplug" + camera;
  DaemonProcess d(kTrackerd,
                  {"--lcm-url", "file://" + out.string() + "?mode=w", "--set", "trackerd.realtime_priority=0", "--set",
                   "trackerd.lock_memory=false", "--deterministic", "--source", "v4l2:" + kNodes, "--set",
                   "camera=" + camera_file(dir.path()).string()},
                  err, {{"CVO_V4L2_EMULATOR", emulated}});
  Run run;
  const auto gone = [&] {
    const auto text = cvo::testing::slurp(err);
    int n = 0;
    for (auto at = text.find("source lost"); at != std::string::npos; at = text.find("source lost", at + 1)) ++n;
    return n >= departures;
  };
  // Waiting for the camera to leave, not timing anything: the bound only ends a broken run.
  for (int i = 0; i < 2400 && !gone() && d.running(); ++i) std::this_thread::sleep_for(cvo::testing::scaled(50ms));
  d.signal(SIGTERM);
  const auto code = d.wait_for(cvo::testing::scaled(60s));
  run.exit_code = code ? *code : -2;
  run.err = cvo::testing::slurp(err);
  run.log = cvo::testing::read_published(out);
  return run;
}

core::Trajectory clip_timed(const std::vector<cvo_lcm::pose_t>& poses, const io::TumSequence& clip) {
  // The poses carry the camera's capture times; pose i is of the clip's entry i (lossless camera).
  core::Trajectory t;
  for (std::size_t i = 0; i < poses.size() && i < clip.size(); ++i)
    t.push_back({clip.files()[i].timestamp, *lcm::from_message(poses[i].odom_pose, nullptr)});
  return t;
}

TEST(TrackerdOnEmulatedV4l2, TracksEveryFrameOfTheClip) {
  const auto run = track("", 1);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ASSERT_EQ(run.log.poses.size(), 50u) << run.err;
  for (std::size_t i = 0; i < run.log.poses.size(); ++i) {
    EXPECT_EQ(run.log.poses[i].frame_index, static_cast<std::int64_t>(i));
    EXPECT_TRUE(run.log.poses[i].status == cvo_lcm::pose_t::STATUS_OK ||
                run.log.poses[i].status == cvo_lcm::pose_t::STATUS_FIRST_FRAME)
        << "frame " << i;
  }
  ASSERT_FALSE(run.log.statuses.empty());
  EXPECT_EQ(run.log.statuses.back().dropped_frames, 0);

  // Through YUYV and millimetre depth, the same bounds as cvo-trackerd on the folder itself
  // (tests/trackerd/trackerd_test.cpp).
  const auto clip = io::TumSequence::open(cvo::testing::kEmulatedClip);
  const auto estimate = clip_timed(run.log.poses, clip);
  const auto rpe = eval::relative_pose_error(clip.groundtruth(), estimate);
  const auto ate = eval::absolute_trajectory_error(clip.groundtruth(), estimate);
  std::printf("cvo-trackerd on fr1_rpy_50 through emulated V4L2 (YUYV, Z16 mm): RPE %.4f m/s %.3f deg/s, ATE %.4f m\n",
              rpe.translation.rmse, rpe.rotation_deg.rmse, ate.error.rmse);
  EXPECT_LT(rpe.translation.rmse, 0.10);
  EXPECT_LT(rpe.rotation_deg.rmse, 8.0);
  EXPECT_LT(ate.error.rmse, 0.06);
}

TEST(TrackerdOnEmulatedV4l2, UnplugMidClipIsAGapAndTrackingResumesInANewSession) {
  const auto run = track(",unplug_after=25,replug_after_s=0.3", 2);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ASSERT_EQ(run.log.poses.size(), 50u) << "25 frames, the unplug, the other 25\n" << run.err;
  std::vector<std::int64_t> sessions;
  for (const auto& p : run.log.poses)
    if (sessions.empty() || sessions.back() != p.session) sessions.push_back(p.session);
  ASSERT_EQ(sessions.size(), 2u) << "a camera that comes back is a new session";
  EXPECT_EQ(run.log.poses[25].frame_index, 0) << "frames count from 0 again";
  EXPECT_EQ(run.log.poses[25].session, sessions[1]);
  for (const auto& p : run.log.poses)
    EXPECT_TRUE(p.status == cvo_lcm::pose_t::STATUS_OK || p.status == cvo_lcm::pose_t::STATUS_FIRST_FRAME);
  EXPECT_NE(run.err.find("frames again from v4l2:"), std::string::npos) << run.err;
  ASSERT_FALSE(run.log.statuses.empty());
  EXPECT_EQ(run.log.statuses.back().source_gaps, 2) << "the unplug and the end of the clip";
}

}  // namespace
}  // namespace cvo::drivers
