// cvo-trackerd over real LCM UDP multicast, the way it runs on a robot: a clip converted with
// tum2lcm is played by lcm-logplayer into a running daemon, whose output lcm-logger records; the
// recording is decoded and evaluated against ground truth. CVO_MAPs sent mid-replay must correct
// the map poses that follow only when they place the tracker's own session, are newer than the
// map applied last and move it plausibly (stale, foreign and implausible maps are counted and
// change nothing). The open local graph
// goes out at SIGTERM. Two replays in deterministic mode give identical poses, in two sessions.
//
// Runs only inside tests/support/in-private-netns (CVO_PRIVATE_NETNS=1): a private network
// namespace with lo alone, so no packet can leave the host.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "libcvo/eval/rpe.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/lcm/map_conversion.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/lcm_log.hpp"
#include "tests/support/private_network.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/slowdown.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::DaemonProcess;
using cvo::testing::which;

constexpr const char* kUrl = cvo::testing::kPrivateLcmUrl;
using cvo::testing::kSlowdown;
using cvo::testing::scaled;
const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";

struct Replay {
  cvo::testing::PublishedLog published;
  std::int64_t session = 0;  // as the daemon's log named it at start
  int trackerd_exit = -2;
  double shutdown_ms = 0;
};

// CVO_MAP messages (encoded: a test may send what the daemon must refuse) for the tracker's session.
using MapsFor = std::function<std::vector<std::vector<std::uint8_t>>(std::int64_t session)>;

// The session cvo-trackerd names at start ("session 0x..."), or 0.
std::int64_t logged_session(const fs::path& stderr_file) {
  std::smatch match;
  const std::string text = cvo::testing::slurp(stderr_file);
  if (!std::regex_search(text, match, std::regex("session 0x([0-9a-f]{16})"))) return 0;
  return static_cast<std::int64_t>(std::stoull(match[1].str(), nullptr, 16));
}

// One replay: logger and daemon up, the recording played (at half speed: the daemon tracks every
// frame and nothing queues up in the socket), maps sent from 1 s on, half a second apart, SIGTERM,
// logger stopped.
Replay replay(const fs::path& dir, const fs::path& recording, const std::string& name, const MapsFor& maps) {
  Replay r;
  const auto out = dir / (name + ".lcmlog");
  DaemonProcess logger(
      which("lcm-logger"),
      {"--lcm-url=" + std::string(kUrl), "-c", "CVO_(POSE|KEYFRAME|LOCAL_GRAPH|STATUS)", "-f", out.string()},
      dir / (name + ".logger.txt"));
  DaemonProcess trackerd(fs::path(CVO_TOOLS_DIR) / "cvo-trackerd",
                         {"--source", std::string("lcm:") + kUrl, "--lcm-url", kUrl, "--deterministic", "--set",
                          "trackerd.realtime_priority=0", "--set", "trackerd.lock_memory=false"},
                         dir / (name + ".trackerd.txt"));
  std::this_thread::sleep_for(scaled(700ms));  // both subscribed
  r.session = logged_session(dir / (name + ".trackerd.txt"));
  DaemonProcess player(which("lcm-logplayer"),
                       {"--lcm-url=" + std::string(kUrl), "-s", std::to_string(0.5 / kSlowdown), recording.string()},
                       dir / (name + ".player.txt"));
  std::this_thread::sleep_for(scaled(500ms));
  ::lcm::LCM lcm(kUrl);
  for (const auto& map : maps(r.session)) {
    std::this_thread::sleep_for(scaled(500ms));
    lcm.publish("CVO_MAP", map.data(), static_cast<unsigned>(map.size()));
  }
  EXPECT_TRUE(player.wait_for(scaled(30s))) << "lcm-logplayer did not finish";
  std::this_thread::sleep_for(scaled(1500ms));  // the last frames tracked and published
  const auto t0 = std::chrono::steady_clock::now();
  trackerd.signal(SIGTERM);
  if (const auto code = trackerd.wait_for(scaled(5s))) r.trackerd_exit = *code;
  r.shutdown_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::this_thread::sleep_for(300ms);
  logger.signal(SIGINT);
  EXPECT_TRUE(logger.wait_for(5s));
  r.published = cvo::testing::read_published(out);
  return r;
}

// A map of the back end, of `revision`, that holds `sessions`, one keyframe each.
std::vector<std::uint8_t> map_message(std::uint64_t revision, const std::vector<slam::MapSession>& sessions,
                                      std::int32_t version = cvo_lcm::map_t::SCHEMA_VERSION) {
  slam::Map map;
  map.revision = revision;
  map.sessions = sessions;
  for (const auto& s : sessions) map.keyframes.push_back({s.session, 0, 1305031102.175304, s.correction});
  auto message = lcm::to_message(map, 1);
  message.version = version;
  return lcm::encode(message);
}

// Every message of a replay is of its session, and the open local graph went out at SIGTERM.
void expect_one_complete_session(const Replay& r) {
  const auto& log = r.published;
  EXPECT_NE(r.session, 0);
  for (const auto& p : log.poses) EXPECT_EQ(p.session, r.session);
  for (const auto& k : log.keyframes) EXPECT_EQ(k.session, r.session);
  for (const auto& g : log.local_graphs) EXPECT_EQ(g.session, r.session);
  for (const auto& s : log.statuses) EXPECT_EQ(s.session, r.session);
  ASSERT_FALSE(log.poses.empty());
  ASSERT_EQ(log.local_graphs.size(), log.keyframes.size()) << "the open local graph is published at the end";
  EXPECT_EQ(log.local_graphs.back().keyframe_id, log.keyframes.back().id);
  EXPECT_EQ(log.local_graphs.back().nodes.back().frame_index, log.poses.back().frame_index);
}

TEST(TrackerdNetns, ReplayOverUdpMulticastIsTrackedCorrectedAndRepeatable) {
  if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
  cvo::test::TempDir dir;
  const auto recording = dir.path() / "clip.lcmlog";
  const auto conversion = cvo::testing::run_tool(
      "tum2lcm", cvo::testing::quoted(kClip) + " " + cvo::testing::quoted(recording) + " --colour jpeg", dir.path());
  ASSERT_EQ(conversion.exit_code, 0) << conversion.err;

  // The back end places the tracker's session 1 m along x in the map, after a map that places
  // only another session (at 5 m along y): only the tracker's own entry may move its map poses.
  // Then an older map (replayed) and a newer one that would move the map frame 9 m: both refused,
  // counted, and the correction stays.
  const auto placed = core::SE3::from_translation({1, 0, 0});
  const auto elsewhere = core::SE3::from_translation({0, 5, 0});
  const auto first = replay(dir.path(), recording, "first", [&](std::int64_t session) {
    const std::int64_t other = session ^ 0x5a5a;
    return std::vector<std::vector<std::uint8_t>>{
        map_message(2, {{other, true, other, 1, 0, elsewhere}}),
        map_message(3, {{other, true, other, 1, 0, elsewhere}, {session, true, other, 1, 0, placed}}),
        map_message(2, {{session, true, other, 1, 0, elsewhere}}),
        map_message(4, {{session, true, other, 1, 0, core::SE3::from_translation({10, 0, 0})}})};
  });
  EXPECT_EQ(first.trackerd_exit, 0) << cvo::testing::slurp(dir.path() / "first.trackerd.txt");
  EXPECT_LT(first.shutdown_ms, 1000 * kSlowdown);
  expect_one_complete_session(first);
  const auto& poses = first.published.poses;
  ASSERT_EQ(poses.size(), 50u) << cvo::testing::slurp(dir.path() / "first.trackerd.txt");
  ASSERT_FALSE(first.published.statuses.empty());
  const auto& status = first.published.statuses.back();
  EXPECT_EQ(status.dropped_frames, 0);
  EXPECT_EQ(status.allocations_after_warmup, 0);
  EXPECT_EQ(status.bad_messages[cvo_lcm::status_t::BAD_FOREIGN], 1);
  EXPECT_EQ(status.bad_messages[cvo_lcm::status_t::BAD_STALE], 1);
  EXPECT_EQ(status.bad_messages[cvo_lcm::status_t::BAD_IMPLAUSIBLE], 1);
  std::printf("UDP replay: end-to-end latency (receipt to publication) median %.2f ms, p99 %.2f ms; shutdown %.0f ms\n",
              status.latency_median_ms, status.latency_p99_ms, first.shutdown_ms);

  // Before its session is placed, map pose = odometry pose (flagged unplaced); after it,
  // map pose = T_map_odom * odometry pose, flagged placed.
  int corrected = 0;
  for (const auto& p : poses) {
    const auto odom = *lcm::from_message(p.odom_pose, nullptr);
    const auto mapped = *lcm::from_message(p.map_pose, nullptr);
    if (p.map_placed) {
      ++corrected;
      EXPECT_LT((mapped.translation() - (placed * odom).translation()).norm(), 1e-9) << "frame " << p.frame_index;
    } else {
      EXPECT_LT((mapped.translation() - odom.translation()).norm(), 1e-12) << "frame " << p.frame_index;
    }
  }
  EXPECT_GT(corrected, 10) << "poses after the map that places the session carry its correction";
  EXPECT_LT(corrected, 50) << "poses before it do not";

  core::Trajectory estimate;
  for (const auto& p : poses) estimate.push_back({lcm::from_utime(p.utime), *lcm::from_message(p.odom_pose, nullptr)});
  const auto rpe = eval::relative_pose_error(io::TumSequence::open(kClip).groundtruth(), estimate);
  EXPECT_LT(rpe.translation.rmse, 0.10);  // the bounds of the library's KF-CVO test on this clip
  EXPECT_LT(rpe.rotation_deg.rmse, 8.0);

  // A second start is another session. Its maps name it unplaced (with a correction that must not
  // be applied), and one says it is schema version 1: refused and counted, never applied.
  const auto second = replay(dir.path(), recording, "second", [&](std::int64_t session) {
    return std::vector<std::vector<std::uint8_t>>{map_message(1, {{session, true, session, 1, 0, placed}}, 1),
                                                  map_message(1, {{session, false, session, 1, -1, elsewhere}})};
  });
  EXPECT_EQ(second.trackerd_exit, 0);
  expect_one_complete_session(second);
  EXPECT_NE(second.session, first.session);
  ASSERT_EQ(second.published.poses.size(), poses.size());
  for (const auto& p : second.published.poses) {
    EXPECT_FALSE(p.map_placed) << "frame " << p.frame_index;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(p.map_pose.position[k], p.odom_pose.position[k]) << "frame " << p.frame_index;
  }
  ASSERT_FALSE(second.published.statuses.empty());
  EXPECT_EQ(second.published.statuses.back().bad_messages[cvo_lcm::status_t::BAD_VERSION], 1);
  for (std::size_t i = 0; i < poses.size(); ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(second.published.poses[i].odom_pose.position[k], poses[i].odom_pose.position[k]) << "frame " << i;
}

}  // namespace
}  // namespace cvo::daemon
