// cvo-trackerd over real LCM UDP multicast, the way it runs on a robot: a clip converted with
// tum2lcm is played by lcm-logplayer into a running daemon, whose output is recorded (as lcm-logger would); the
// recording is decoded and evaluated against ground truth. CVO_MAPs sent mid-replay must correct
// the map poses that follow only when they place the tracker's own session, are newer than the
// map applied last and move it plausibly (stale, foreign and implausible maps are counted and
// change nothing); so must CVO_MAP_CORRECTIONs alone, another session's ignored. The open local graph
// goes out at SIGTERM. Two replays in deterministic mode give identical poses, in two sessions.
//
// Runs only inside tests/support/in-private-netns (CVO_PRIVATE_NETNS=1): a private network
// namespace with lo alone, so no packet can leave the host.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <mutex>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/keyframe_chunk_t.hpp"
#include "cvo_lcm/keyframe_request_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "libcvo/core/units.hpp"
#include "libcvo/eval/rpe.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/map_conversion.hpp"
#include "libcvo/lcm/map_correction_conversion.hpp"
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

// CVO_MAP (or CVO_MAP_CORRECTION) messages (encoded: a test may send what the daemon must refuse)
// for the tracker's session.
using MapsFor = std::function<std::vector<std::vector<std::uint8_t>>(std::int64_t session)>;

// The session cvo-trackerd names at start ("session 0x..."), or 0.
std::int64_t logged_session(const fs::path& stderr_file) {
  std::smatch match;
  const std::string text = cvo::testing::slurp(stderr_file);
  if (!std::regex_search(text, match, std::regex("session 0x([0-9a-f]{16})"))) return 0;
  return static_cast<std::int64_t>(std::stoull(match[1].str(), nullptr, 16));
}

// One replay: logger and daemon up, the recording played (at 0.3 times its speed: the daemon tracks
// every frame, nothing queues up in the socket, and every map comes mid-clip), maps sent on
// `channel` from 0.75 s on, a quarter of a second apart, SIGTERM (no linger: the maps' back end
// is the test, which holds no keyframe), logger stopped.
Replay replay(const fs::path& dir, const fs::path& recording, const std::string& name, const MapsFor& maps,
              const std::string& channel = "CVO_MAP") {
  Replay r;
  const auto out = dir / (name + ".lcmlog");
  auto logger =
      std::make_unique<cvo::testing::LcmRecorder>(kUrl, "CVO_(POSE|KEYFRAME|KEYFRAME_CHUNK|LOCAL_GRAPH|STATUS)", out);
  EXPECT_TRUE(logger->good());
  DaemonProcess trackerd(
      fs::path(CVO_TOOLS_DIR) / "cvo-trackerd",
      {"--source", std::string("lcm:") + kUrl, "--lcm-url", kUrl, "--deterministic", "--set",
       "trackerd.realtime_priority=0", "--set", "trackerd.lock_memory=false", "--set", "trackerd.linger_s=0"},
      dir / (name + ".trackerd.txt"));
  std::this_thread::sleep_for(scaled(700ms));  // both subscribed
  r.session = logged_session(dir / (name + ".trackerd.txt"));
  DaemonProcess player(which("lcm-logplayer"),
                       {"--lcm-url=" + std::string(kUrl), "-s", std::to_string(0.3 / kSlowdown), recording.string()},
                       dir / (name + ".player.txt"));
  std::this_thread::sleep_for(scaled(500ms));
  ::lcm::LCM lcm(kUrl);
  for (const auto& map : maps(r.session)) {
    std::this_thread::sleep_for(scaled(250ms));
    lcm.publish(channel, map.data(), static_cast<unsigned>(map.size()));
  }
  EXPECT_TRUE(player.wait_for(scaled(30s))) << "lcm-logplayer did not finish";
  std::this_thread::sleep_for(scaled(1500ms));  // the last frames tracked and published
  const auto t0 = std::chrono::steady_clock::now();
  trackerd.signal(SIGTERM);
  if (const auto code = trackerd.wait_for(scaled(5s))) r.trackerd_exit = *code;
  r.shutdown_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::this_thread::sleep_for(300ms);
  logger.reset();  // the log complete
  r.published = cvo::testing::read_published(out);
  return r;
}

// A map of the back end, of `revision`, that holds `sessions`, one keyframe each.
std::vector<std::uint8_t> map_message(std::uint64_t revision, const std::vector<slam::MapSession>& sessions,
                                      std::int32_t version = cvo_lcm::map_t::SCHEMA_VERSION, std::int64_t epoch = 0) {
  slam::Map map;
  map.revision = revision;
  map.sessions = sessions;
  for (const auto& s : sessions) map.keyframes.push_back({s.session, 0, 1305031102.175304, s.correction});
  auto message = lcm::to_message(map, 1, epoch);
  message.version = version;
  return lcm::encode(message);
}

// A CVO_MAP_CORRECTION of the back end (epoch 0), of `revision`, for one session's entry. It
// acknowledges nothing (a back end never says it holds more than was published, issue 48): replay()
// sets no linger, so the tracker does not wait for it at its exit.
std::vector<std::uint8_t> correction_message(std::uint64_t revision, const slam::MapSession& session) {
  return lcm::encode(lcm::to_message(slam::SessionCorrection{revision, session, {}}, 1, 0, 0));
}

// Every message of a replay is of its session, every keyframe has its local graph, and the open
// local graph went out at SIGTERM. Counted by id: a back end that was heard but acknowledges nothing
// (the test's) has the tracker send keyframes again.
void expect_one_complete_session(const Replay& r) {
  const auto& log = r.published;
  EXPECT_NE(r.session, 0);
  for (const auto& p : log.poses) EXPECT_EQ(p.session, r.session);
  for (const auto& k : log.keyframes) EXPECT_EQ(k.session, r.session);
  for (const auto& g : log.local_graphs) EXPECT_EQ(g.session, r.session);
  for (const auto& s : log.statuses) EXPECT_EQ(s.session, r.session);
  ASSERT_FALSE(log.poses.empty());
  ASSERT_FALSE(log.keyframes.empty());
  EXPECT_GT(log.keyframe_chunks, 0) << "on a network keyframes go in slices (trackerd.keyframe_transport auto)";
  std::set<std::int64_t> keyframes, graphs;
  for (const auto& k : log.keyframes) keyframes.insert(k.id);
  for (const auto& g : log.local_graphs) graphs.insert(g.keyframe_id);
  ASSERT_EQ(graphs, keyframes) << "the open local graph is published at the end";
  const auto open = std::find_if(log.local_graphs.rbegin(), log.local_graphs.rend(),
                                 [&](const cvo_lcm::local_graph_t& g) { return g.keyframe_id == *keyframes.rbegin(); });
  EXPECT_EQ(open->nodes.back().frame_index, log.poses.back().frame_index);
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
  // counted, and the correction stays. Then the attacks of issue 26 that an open bus let through
  // (the guards of libcvo/lcm/map_decision.hpp): a map of an epoch a year ahead, one whose revision
  // leaps a million, "unplaced" followed by "placed 100 m away": all refused, and the genuine back
  // end's next map (revision 5) is still applied.
  const auto placed = core::SE3::from_translation({1, 0, 0});
  const auto elsewhere = core::SE3::from_translation({0, 5, 0});
  const std::int64_t in_a_year = core::wall_utime() + 365LL * 86400 * 1'000'000;
  const auto first = replay(dir.path(), recording, "first", [&](std::int64_t session) {
    const std::int64_t other = session ^ 0x5a5a;
    const slam::MapSession genuine{session, true, other, 1, 0, placed};
    const auto kAt = [&](const core::SE3& correction) {
      return std::vector<slam::MapSession>{{session, true, other, 1, 0, correction}};
    };
    return std::vector<std::vector<std::uint8_t>>{
        map_message(2, {{other, true, other, 1, 0, elsewhere}}),
        map_message(3, {{other, true, other, 1, 0, elsewhere}, genuine}),
        map_message(2, {{session, true, other, 1, 0, elsewhere}}),
        map_message(4, kAt(core::SE3::from_translation({10, 0, 0}))),
        map_message(1, kAt(core::SE3::from_translation({0.5, 0, 0})), cvo_lcm::map_t::SCHEMA_VERSION, in_a_year),
        map_message(1'000'000, kAt(core::SE3::from_translation({1.5, 0, 0}))),
        map_message(4, {{session, false, session, 1, -1, {}}}),
        map_message(4, kAt(core::SE3::from_translation({100, 0, 0}))),
        map_message(5, {genuine})};
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
  EXPECT_EQ(status.bad_messages[cvo_lcm::status_t::BAD_IMPLAUSIBLE], 4) << "9 m, a year ahead, the leap, 100 m";
  EXPECT_EQ(status.bad_messages[cvo_lcm::status_t::BAD_CONFLICT], 1) << "unplaced within the epoch";
  EXPECT_EQ(poses.back().map_revision, 5) << "the genuine back end is not locked out";
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

// The back end's word on CVO_MAP_CORRECTION alone, no CVO_MAP at all (issue 27): another session's
// correction is ignored (every tracker hears every session's: no fault counted); the tracker's own,
// placing it 1 m along x, is applied, and the same sent again (the back end re-sends) is ignored;
// an older one is stale, one 9 m further implausible; the back end's next (revision 5) is applied.
TEST(TrackerdNetns, ACorrectionAloneMovesTheMapPosesAndTheGuardsHold) {
  if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
  cvo::test::TempDir dir;
  const auto recording = dir.path() / "clip.lcmlog";
  const auto conversion = cvo::testing::run_tool(
      "tum2lcm", cvo::testing::quoted(kClip) + " " + cvo::testing::quoted(recording) + " --colour jpeg", dir.path());
  ASSERT_EQ(conversion.exit_code, 0) << conversion.err;
  const auto placed = core::SE3::from_translation({1, 0, 0});
  const auto r = replay(
      dir.path(), recording, "corrections",
      [&](std::int64_t session) {
        const std::int64_t other = session ^ 0x5a5a;
        const auto at = [&](const core::SE3& correction) {
          return slam::MapSession{session, true, other, 1, 0, correction};
        };
        return std::vector<std::vector<std::uint8_t>>{
            correction_message(2, {other, true, other, 1, 0, core::SE3::from_translation({0, 5, 0})}),
            correction_message(3, at(placed)),
            correction_message(3, at(placed)),
            correction_message(2, at(core::SE3::from_translation({1.2, 0, 0}))),
            correction_message(4, at(core::SE3::from_translation({10, 0, 0}))),
            correction_message(5, at(placed))};
      },
      "CVO_MAP_CORRECTION");
  EXPECT_EQ(r.trackerd_exit, 0) << cvo::testing::slurp(dir.path() / "corrections.trackerd.txt");
  expect_one_complete_session(r);
  const auto& poses = r.published.poses;
  ASSERT_EQ(poses.size(), 50u) << cvo::testing::slurp(dir.path() / "corrections.trackerd.txt");
  ASSERT_FALSE(r.published.statuses.empty());
  const auto& status = r.published.statuses.back();
  EXPECT_EQ(status.bad_messages[cvo_lcm::status_t::BAD_FOREIGN], 0) << "another session's correction is no fault";
  EXPECT_EQ(status.bad_messages[cvo_lcm::status_t::BAD_STALE], 1) << "revision 2 after 3; the repeat is no fault";
  EXPECT_EQ(status.bad_messages[cvo_lcm::status_t::BAD_IMPLAUSIBLE], 1) << "9 m";
  EXPECT_EQ(poses.back().map_revision, 5);
  int corrected = 0;
  for (const auto& p : poses) {
    const auto odom = *lcm::from_message(p.odom_pose, nullptr);
    const auto mapped = *lcm::from_message(p.map_pose, nullptr);
    if (!p.map_placed) {
      EXPECT_LT((mapped.translation() - odom.translation()).norm(), 1e-12) << "frame " << p.frame_index;
      continue;
    }
    ++corrected;
    EXPECT_LT((mapped.translation() - (placed * odom).translation()).norm(), 1e-9) << "frame " << p.frame_index;
    EXPECT_GE(p.map_revision, 3) << "frame " << p.frame_index;
  }
  EXPECT_GT(corrected, 10) << "poses after the correction that places the session carry it";
  EXPECT_LT(corrected, 50) << "poses before it do not";
  const std::string log = cvo::testing::slurp(dir.path() / "corrections.trackerd.txt");
  EXPECT_NE(log.find("placed in the map (map revision 3, CVO_MAP_CORRECTION)"), std::string::npos) << log;
}

// The amplification of issue 26: 50 requests (each for 16 keyframes, under 10 kB in all) made the
// tracker send 796 keyframes, 210 MB, in 5 s. Now a live tracker on the clip (it stays up after
// its last frame, as a robot's does), asked 50 times in a second for every keyframe it made, sends
// again at most trackerd.resend_bytes_per_s a second plus one second's worth, and notes the rest.
TEST(TrackerdNetns, AFloodOfKeyframeRequestsReSendsAtMostTheBudget) {
  if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
  cvo::test::TempDir dir;
  constexpr double kBudget = 1e6;  // bytes a second
  const auto err = dir.path() / "trackerd.txt";
  DaemonProcess trackerd(fs::path(CVO_TOOLS_DIR) / "cvo-trackerd",
                         {"--source", "tum:" + kClip.string(), "--lcm-url", kUrl, "--deterministic", "--set",
                          "trackerd.realtime_priority=0", "--set", "trackerd.lock_memory=false", "--set",
                          "trackerd.resend_bytes_per_s=" + std::to_string(kBudget)},
                         err);
  struct Seen {
    std::mutex mutex;
    std::int64_t session = 0, newest_keyframe = -1, last_frame = -1;
    double keyframe_bytes = 0;  // keyframes and local graphs after the flood began
    int keyframes = 0;
    bool flooding = false;
    void pose(const ::lcm::ReceiveBuffer* b, const std::string&) {
      const auto p = lcm::decode<cvo_lcm::pose_t>(b->data, static_cast<int>(b->data_size), nullptr);
      if (!p) return;
      const std::lock_guard lock(mutex);
      session = p->session;
      newest_keyframe = std::max(newest_keyframe, p->keyframe_id);
      last_frame = std::max(last_frame, p->frame_index);
    }
    void keyframe(const ::lcm::ReceiveBuffer* b, const std::string& channel) {
      const std::lock_guard lock(mutex);
      if (!flooding) return;
      if (channel == "CVO_KEYFRAME") {
        keyframe_bytes += static_cast<double>(b->data_size);
        ++keyframes;
        return;
      }
      // In slices (on a network, the tracker's default): the bytes of the messages, a keyframe per first slice.
      const auto slice = lcm::decode<cvo_lcm::keyframe_chunk_t>(b->data, static_cast<int>(b->data_size), nullptr);
      if (!slice) return;
      keyframe_bytes += slice->data_size;
      if (slice->message == cvo_lcm::keyframe_chunk_t::KEYFRAME && slice->index == 0) ++keyframes;
    }
  } seen;
  ::lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  lcm.subscribe("CVO_POSE", &Seen::pose, &seen);
  lcm.subscribe("CVO_KEYFRAME", &Seen::keyframe, &seen);
  lcm.subscribe("CVO_KEYFRAME_CHUNK", &Seen::keyframe, &seen)->setQueueCapacity(100000);
  const auto handle_for = [&](std::chrono::duration<double> d) {
    const auto end = std::chrono::steady_clock::now() + d;
    while (std::chrono::steady_clock::now() < end) lcm.handleTimeout(20);
  };
  for (int i = 0; i < 600; ++i) {  // until the clip's 50 frames are tracked (at most a minute)
    handle_for(100ms);
    const std::lock_guard lock(seen.mutex);
    if (seen.last_frame == 49) break;
  }
  ASSERT_EQ(seen.last_frame, 49) << cvo::testing::slurp(err);
  ASSERT_GE(seen.newest_keyframe, 3) << "too few keyframes to flood with";
  handle_for(500ms);  // the last keyframe's messages are out

  cvo_lcm::keyframe_request_t request{};
  request.version = cvo_lcm::keyframe_request_t::SCHEMA_VERSION;
  request.session = seen.session;
  for (std::int64_t id = 0; id <= seen.newest_keyframe && id < cvo_lcm::keyframe_request_t::MAX_IDS; ++id)
    request.ids.push_back(id);
  request.num_ids = static_cast<std::int32_t>(request.ids.size());
  const auto t0 = std::chrono::steady_clock::now();
  seen.flooding = true;
  for (int i = 0; i < 50; ++i) {
    request.utime = core::wall_utime();
    lcm.publish("CVO_KEYFRAME_REQUEST", &request);
    handle_for(20ms);
  }
  handle_for(1s);  // what the flood set going
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::lock_guard lock(seen.mutex);
  std::printf("50 requests for %d keyframes in 1 s: %d keyframes (%.0f kB) sent again in %.1f s (budget %.0f kB/s)\n",
              request.num_ids, seen.keyframes, seen.keyframe_bytes / 1e3, elapsed, kBudget / 1e3);
  EXPECT_GT(seen.keyframes, 0) << "a genuine request is still answered";
  // The bound, with one keyframe of slack for the bucket that a full one lets go into debt.
  const double one_keyframe = seen.keyframes > 0 ? seen.keyframe_bytes / seen.keyframes : 0;
  EXPECT_LE(seen.keyframe_bytes, kBudget * (elapsed + 1) + one_keyframe);
  EXPECT_LT(seen.keyframes, 50 * request.num_ids / 4) << "without the budget every request is answered whole";
  trackerd.signal(SIGTERM);
  EXPECT_EQ(trackerd.wait_for(scaled(10s)).value_or(-9), 0);
  EXPECT_NE(cvo::testing::slurp(err).find("over trackerd.resend_bytes_per_s"), std::string::npos)
      << cvo::testing::slurp(err);
}

}  // namespace
}  // namespace cvo::daemon
