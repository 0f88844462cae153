// cvo-trackerd over real LCM UDP multicast, the way it runs on a robot: a clip converted with
// tum2lcm is played by lcm-logplayer into a running daemon, whose output lcm-logger records; the
// recording is decoded and evaluated against ground truth. A CVO_MAP sent mid-replay must correct
// the map poses that follow. Two replays in deterministic mode give identical poses.
//
// Runs only inside tests/support/in-private-netns (CVO_PRIVATE_NETNS=1): a private network
// namespace with lo alone, so no packet can leave the host.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "libcvo/eval/rpe.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "tests/daemon/daemon_process.hpp"
#include "tests/daemon/lcm_log.hpp"
#include "tests/daemon/private_network.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::DaemonProcess;
using cvo::testing::which;

constexpr const char* kUrl = cvo::testing::kPrivateLcmUrl;
const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";

struct Replay {
  cvo::testing::PublishedLog published;
  int trackerd_exit = -2;
  double shutdown_ms = 0;
};

// One replay: logger and daemon up, the recording played (at half speed: the daemon tracks every
// frame and nothing queues up in the socket), a map sent half-way, SIGTERM, logger stopped.
Replay replay(const fs::path& dir, const fs::path& recording, const std::string& name, const cvo_lcm::map_t* map) {
  Replay r;
  const auto out = dir / (name + ".lcmlog");
  DaemonProcess logger(which("lcm-logger"), {"--lcm-url=" + std::string(kUrl), "-c", "CVO_(POSE|KEYFRAME|LOCAL_GRAPH|STATUS)", "-f", out.string()},
                       dir / (name + ".logger.txt"));
  DaemonProcess trackerd(fs::path(CVO_TOOLS_DIR) / "cvo-trackerd",
                         {"--source", std::string("lcm:") + kUrl, "--lcm-url", kUrl, "--deterministic", "--set",
                          "trackerd.realtime_priority=0", "--set", "trackerd.lock_memory=false"},
                         dir / (name + ".trackerd.txt"));
  std::this_thread::sleep_for(700ms);  // both subscribed
  DaemonProcess player(which("lcm-logplayer"), {"--lcm-url=" + std::string(kUrl), "-s", "0.5", recording.string()},
                       dir / (name + ".player.txt"));
  if (map != nullptr) {
    std::this_thread::sleep_for(1500ms);
    ::lcm::LCM lcm(kUrl);
    lcm.publish("CVO_MAP", map);
  }
  EXPECT_TRUE(player.wait_for(30s)) << "lcm-logplayer did not finish";
  std::this_thread::sleep_for(1500ms);  // the last frames tracked and published
  const auto t0 = std::chrono::steady_clock::now();
  trackerd.signal(SIGTERM);
  if (const auto code = trackerd.wait_for(5s)) r.trackerd_exit = *code;
  r.shutdown_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::this_thread::sleep_for(300ms);
  logger.signal(SIGINT);
  EXPECT_TRUE(logger.wait_for(5s));
  r.published = cvo::testing::read_published(out);
  return r;
}

TEST(TrackerdNetns, ReplayOverUdpMulticastIsTrackedCorrectedAndRepeatable) {
  if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
  cvo::test::TempDir dir;
  const auto recording = dir.path() / "clip.lcmlog";
  const auto conversion = cvo::testing::run_tool(
      "tum2lcm", cvo::testing::quoted(kClip) + " " + cvo::testing::quoted(recording) + " --colour jpeg", dir.path());
  ASSERT_EQ(conversion.exit_code, 0) << conversion.err;

  // The back end says keyframe 0 (the first frame, odometry origin) is at 1 m along x in the map.
  cvo_lcm::map_t map{};
  map.version = cvo_lcm::map_t::SCHEMA_VERSION;
  map.revision = 1;
  map.num_keyframes = 1;
  map.keyframe_ids = {0};
  map.poses = {lcm::to_message(core::SE3::from_translation({1, 0, 0}))};

  const auto first = replay(dir.path(), recording, "first", &map);
  EXPECT_EQ(first.trackerd_exit, 0) << cvo::testing::slurp(dir.path() / "first.trackerd.txt");
  EXPECT_LT(first.shutdown_ms, 1000);
  const auto& poses = first.published.poses;
  ASSERT_EQ(poses.size(), 50u) << cvo::testing::slurp(dir.path() / "first.trackerd.txt");
  ASSERT_FALSE(first.published.statuses.empty());
  const auto& status = first.published.statuses.back();
  EXPECT_EQ(status.dropped_frames, 0);
  EXPECT_EQ(status.allocations_after_warmup, 0);
  std::printf("UDP replay: end-to-end latency (receipt to publication) median %.2f ms, p99 %.2f ms; shutdown %.0f ms\n",
              status.latency_median_ms, status.latency_p99_ms, first.shutdown_ms);

  // Before the map, map pose = odometry pose; after it, map pose = T_map_odom * odometry pose.
  int corrected = 0;
  for (const auto& p : poses) {
    const auto odom = *lcm::from_message(p.odom_pose, nullptr);
    const auto mapped = *lcm::from_message(p.map_pose, nullptr);
    const double dx = (mapped.translation() - odom.translation()).x();
    if (std::abs(dx - 1.0) < 1e-9) ++corrected;
    else EXPECT_LT((mapped.translation() - odom.translation()).norm(), 1e-12) << "frame " << p.frame_index;
  }
  EXPECT_GT(corrected, 10) << "poses after CVO_MAP carry its correction";
  EXPECT_LT(corrected, 50) << "poses before it do not";

  core::Trajectory estimate;
  for (const auto& p : poses) estimate.push_back({lcm::from_utime(p.utime), *lcm::from_message(p.odom_pose, nullptr)});
  const auto rpe = eval::relative_pose_error(io::TumSequence::open(kClip).groundtruth(), estimate);
  EXPECT_LT(rpe.translation.rmse, 0.10);  // the bounds of the library's KF-CVO test on this clip
  EXPECT_LT(rpe.rotation_deg.rmse, 8.0);

  const auto second = replay(dir.path(), recording, "second", nullptr);
  EXPECT_EQ(second.trackerd_exit, 0);
  ASSERT_EQ(second.published.poses.size(), poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(second.published.poses[i].odom_pose.position[k], poses[i].odom_pose.position[k]) << "frame " << i;
}

}  // namespace
}  // namespace cvo::daemon
