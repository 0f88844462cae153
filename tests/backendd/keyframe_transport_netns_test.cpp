// No keyframe lost in transport: a real cvo-trackerd on the embedded clip publishes on one LCM
// multicast group, a real cvo-backendd listens on another, and a relay between them (this test) is
// the lossy link. It forwards CVO_KEYFRAME, CVO_KEYFRAME_CHUNK, CVO_LOCAL_GRAPH, CVO_POSE and
// CVO_STATUS (a tracker whose clip has ended is heard by its status alone) to the back end,
// CVO_KEYFRAME_REQUEST, CVO_MAP_CORRECTION and CVO_MAP to the tracker, and loses:
// - keyframes sent whole (trackerd.keyframe_transport whole): every third keyframe the first five
//   times it is sent (the back end asked four times before issue 28: these would have been lost);
// - keyframes in slices (the default on a network): 10 % or 30 % of the datagrams each way, at
//   random (each slice, pose, status, request is one datagram; before issue 28 a keyframe of ~200
//   packets was lost whole to one of them).
// The back end notices each gap or missing slice, asks the tracker again, and its map holds every
// keyframe the tracker made while the tracker still runs, and its final map (after SIGTERM) too;
// both processes' CVO_STATUS count what was asked for and recovered, and nothing lost.
//
// Runs only inside tests/support/in-private-netns (CVO_PRIVATE_NETNS=1): lo alone, no packet can
// leave the host.
#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/keyframe_chunk_t.hpp"
#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "libcvo/lcm/decode.hpp"
#include "tests/backendd/netns_support.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::Captured;
using cvo::testing::DaemonProcess;
using cvo::testing::KeyframeName;
using cvo::testing::LcmCapture;

const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";
// The tracker's side of the relay: another group and port than the back end's (cvo::testing::kUrl).
constexpr const char* kTrackerUrl = "udpm://239.255.76.68:7668?ttl=0&recv_buf_size=8388608";

// What the relay saw and did; read under Relay::mutex_.
struct RelayLog {
  std::set<KeyframeName> made;                      // every keyframe the tracker's poses name (ids from 0)
  std::set<KeyframeName> sent;                      // every keyframe the tracker sent (whole, or a slice of it)
  std::set<KeyframeName> dropped;                   // whole keyframes lost on purpose at least once
  int resent = 0;                                   // keyframes (whole) or slices sent again that passed
  int datagrams = 0, lost = 0;                      // messages that came to the relay, and that it lost
  int requests = 0;                                 // CVO_KEYFRAME_REQUESTs passed to the tracker
  std::int64_t last_frame = -1;                     // the newest frame index of the tracker's poses
  std::optional<cvo_lcm::status_t> tracker_status;  // the tracker's newest CVO_STATUS
};

// Which message the relay loses: whole keyframes by rule, or every datagram at random.
struct Loss {
  bool every_third_keyframe = false;  // every third whole keyframe, its first kDroppedSends sends
  int percent = 0;                    // of every datagram, both ways
};

class Relay {
 public:
  explicit Relay(Loss loss) : loss_(loss), tracker_side_(kTrackerUrl), backend_side_(cvo::testing::kUrl) {
    for (const char* channel : {"CVO_KEYFRAME", "CVO_KEYFRAME_CHUNK", "CVO_LOCAL_GRAPH", "CVO_POSE", "CVO_STATUS"})
      tracker_side_.subscribe(channel, &Relay::from_tracker, this)->setQueueCapacity(10000);  // bursts of slices
    for (const char* channel : {"CVO_KEYFRAME_REQUEST", "CVO_MAP_CORRECTION", "CVO_MAP"})
      backend_side_.subscribe(channel, &Relay::from_backend, this);
    threads_.emplace_back([this] { run(tracker_side_, "relay-tracker"); });
    threads_.emplace_back([this] { run(backend_side_, "relay-backend"); });
  }
  ~Relay() {
    stop_ = true;
    for (auto& t : threads_) t.join();
  }
  Relay(const Relay&) = delete;
  Relay& operator=(const Relay&) = delete;

  [[nodiscard]] bool good() { return tracker_side_.good() && backend_side_.good(); }
  RelayLog snapshot() {
    const std::lock_guard lock(mutex_);
    return log_;
  }
  /// True once `condition` holds for what the relay saw; false when `limit` passed first.
  bool wait_until(const std::function<bool(const RelayLog&)>& condition, std::chrono::seconds limit) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, limit, [&] { return condition(log_); });
  }

 private:
  void run(::lcm::LCM& lcm, const char* name) {
    pthread_setname_np(pthread_self(), name);
    while (!stop_) lcm.handleTimeout(50);
  }

  void from_tracker(const ::lcm::ReceiveBuffer* buffer, const std::string& channel) {
    const auto size = static_cast<int>(buffer->data_size);
    if (channel == "CVO_STATUS") {  // for the test, and for the back end: the tracker is alive
      if (auto s = lcm::decode<cvo_lcm::status_t>(buffer->data, size, nullptr); s && s->process == "cvo-trackerd") {
        const std::lock_guard lock(mutex_);
        log_.tracker_status = std::move(*s);
      }
      changed_.notify_all();
    }
    if (channel == "CVO_POSE") note_pose(buffer->data, size);
    if (channel == "CVO_KEYFRAME" && !pass_keyframe(buffer->data, size)) return;
    if (channel == "CVO_KEYFRAME_CHUNK") note_slice(buffer->data, size);
    if (lose()) return;
    backend_side_.publish(channel, buffer->data, buffer->data_size);
  }

  void from_backend(const ::lcm::ReceiveBuffer* buffer, const std::string& channel) {
    if (lose()) return;
    if (channel == "CVO_KEYFRAME_REQUEST") {
      const std::lock_guard lock(mutex_);
      ++log_.requests;
    }
    tracker_side_.publish(channel, buffer->data, buffer->data_size);
  }

  // A datagram lost at random (Loss::percent), counted.
  bool lose() {
    const std::lock_guard lock(mutex_);
    ++log_.datagrams;
    const bool lost = std::uniform_int_distribution<int>(0, 99)(random_) < loss_.percent;
    log_.lost += lost ? 1 : 0;
    return lost;
  }

  void note_slice(const void* data, int size) {
    const auto chunk = lcm::decode<cvo_lcm::keyframe_chunk_t>(data, size, nullptr);
    if (!chunk) return;
    const std::lock_guard lock(mutex_);
    if (chunk->message == cvo_lcm::keyframe_chunk_t::KEYFRAME) log_.sent.emplace(chunk->session, chunk->id);
    if (!slices_.emplace(chunk->session, chunk->id, chunk->message, chunk->index).second) ++log_.resent;
  }

  void note_pose(const void* data, int size) {
    const auto pose = lcm::decode<cvo_lcm::pose_t>(data, size, nullptr);
    if (!pose) return;
    {
      const std::lock_guard lock(mutex_);
      for (std::int64_t id = 0; id <= pose->keyframe_id; ++id) log_.made.emplace(pose->session, id);
      log_.last_frame = std::max(log_.last_frame, pose->frame_index);
    }
    changed_.notify_all();
  }

  // Every third keyframe is lost the first kDroppedSends times it is sent; later sends pass.
  static constexpr int kDroppedSends = 5;
  bool pass_keyframe(const void* data, int size) {
    const auto keyframe = lcm::decode<cvo_lcm::keyframe_t>(data, size, nullptr);
    if (!keyframe) return true;
    const KeyframeName name{keyframe->session, keyframe->id};
    const std::lock_guard lock(mutex_);
    const int sends = ++sends_[name];
    if (sends == 1 && log_.sent.insert(name).second && loss_.every_third_keyframe && log_.sent.size() % 3 == 0)
      log_.dropped.insert(name);
    if (log_.dropped.contains(name) && sends <= kDroppedSends) return false;
    if (sends > 1) ++log_.resent;
    return true;
  }
  std::map<KeyframeName, int> sends_;                                                   // under mutex_
  std::set<std::tuple<std::int64_t, std::int64_t, std::int8_t, std::int32_t>> slices_;  // seen; under mutex_
  const Loss loss_;
  std::mt19937 random_{28};  // under mutex_

  ::lcm::LCM tracker_side_, backend_side_;
  std::mutex mutex_;
  std::condition_variable changed_;
  RelayLog log_;
  std::atomic<bool> stop_{false};
  std::vector<std::thread> threads_;
};

// A live tracker at the clip's 30 Hz (`settings` added) that stays up after its last frame, as a
// robot's does, so that it can still answer for its newest keyframes; a back end behind the relay.
// Every keyframe the tracker made must reach the back end's map while the tracker runs, and be in
// its final map.
void expect_every_keyframe_arrives(Loss loss, const std::vector<std::string>& settings) {
  cvo::test::TempDir dir;
  LcmCapture capture(dir.path() / "maps.lcmlog");
  ASSERT_TRUE(capture.good());
  Relay relay(loss);
  ASSERT_TRUE(relay.good());

  const auto backend_err = dir.path() / "backendd.txt", tracker_err = dir.path() / "trackerd.txt";
  auto backendd = cvo::testing::start_backendd(dir.path() / "keyframes.store", backend_err);
  const int backend_pid = backendd->pid();
  ASSERT_TRUE(capture.wait_until([&](const Captured& c) { return c.status_from(backend_pid); }, 60s))
      << cvo::testing::slurp(backend_err);

  std::vector<std::string> args{"--source",
                                "tum:" + kClip.string(),
                                "--lcm-url",
                                kTrackerUrl,
                                "--deterministic",
                                "--set",
                                "trackerd.realtime_priority=0",
                                "--set",
                                "trackerd.lock_memory=false"};
  for (const auto& s : settings) args.insert(args.end(), {"--set", s});
  DaemonProcess trackerd(fs::path(CVO_TOOLS_DIR) / "cvo-trackerd", args, tracker_err);
  const auto logs = [&] { return cvo::testing::slurp(tracker_err) + cvo::testing::slurp(backend_err); };

  // Every frame tracked (the clip has 50), then every keyframe it made in the back end's map.
  ASSERT_TRUE(relay.wait_until([](const RelayLog& r) { return r.last_frame == 49; }, 120s)) << logs();
  const RelayLog seen = relay.snapshot();
  ASSERT_GE(seen.made.size(), 6u) << "too few keyframes for the loss to matter";
  if (loss.every_third_keyframe) {
    EXPECT_EQ(seen.dropped.size(), seen.made.size() / 3);
  }
  EXPECT_TRUE(capture.wait_until([&](const Captured& c) { return c.map_holds(seen.made); }, 120s))
      << "not every keyframe reached the map while the tracker runs\n"
      << logs();

  const auto tracker_code = cvo::testing::stop(trackerd, 60s);
  EXPECT_EQ(tracker_code.value_or(-9), 0) << logs();
  EXPECT_TRUE(relay.wait_until(
                  [](const RelayLog& r) {
                    return r.tracker_status && r.tracker_status->state == cvo_lcm::status_t::STATE_STOPPING;
                  },
                  30s) ||
              loss.percent > 0)
      << "no final CVO_STATUS from the tracker";
  const auto backend_code = cvo::testing::stop(*backendd, 120s);
  EXPECT_EQ(backend_code.value_or(-9), 0) << logs();
  ASSERT_TRUE(capture.wait_until(
      [&](const Captured& c) { return c.status_from(backend_pid, +cvo_lcm::status_t::STATE_STOPPING); }, 30s));

  // The final map (published before the final CVO_STATUS) holds every keyframe the tracker made.
  const Captured captured = capture.snapshot();
  ASSERT_TRUE(captured.map);
  EXPECT_TRUE(captured.map_holds(seen.made)) << logs();
  // Listed, or merged into a keyframe that covers it: one that comes seconds late, after both its
  // neighbours, may be (libcvo/slam/mapper.hpp, revisits); its session still counts it.
  EXPECT_LE(captured.map->keyframes.size(), seen.made.size());
  // And every keyframe's local graph, those refused while their keyframe was missing included, and
  // the newest keyframe's, sent as the tracker stops (it lingers until the back end acknowledges it).
  const auto backend_log = cvo::testing::slurp(backend_err);
  std::smatch graphs;
  ASSERT_TRUE(std::regex_search(backend_log, graphs, std::regex("; (\\d+) local graphs;"))) << backend_log;
  EXPECT_EQ(std::stoul(graphs[1]), seen.made.size()) << backend_log;

  const RelayLog relayed = relay.snapshot();
  EXPECT_EQ(relayed.sent, seen.made) << "the tracker sent every keyframe it made";
  const auto& backend = captured.backend_statuses.back();
  const auto tracker = relayed.tracker_status.value_or(cvo_lcm::status_t{});
  std::cout << "loss " << loss.percent << " %: keyframes made " << seen.made.size() << "; relay: datagrams "
            << relayed.datagrams << ", lost " << relayed.lost << ", whole keyframes lost " << relayed.dropped.size()
            << ", requests passed " << relayed.requests << ", sent again " << relayed.resent << "; back end: requested "
            << backend.keyframes_requested << ", recovered " << backend.keyframes_recovered << ", lost "
            << backend.keyframes_lost << ", local graphs refused "
            << backend.bad_messages[cvo_lcm::status_t::BAD_UNKNOWN_KEYFRAME] << "; tracker: sent again "
            << tracker.keyframes_requested << ", lost " << tracker.keyframes_lost << std::endl;
  EXPECT_GE(backend.keyframes_requested, static_cast<std::int64_t>(relayed.dropped.size()));
  EXPECT_EQ(backend.keyframes_recovered, backend.keyframes_requested) << logs();
  EXPECT_EQ(backend.keyframes_lost, 0) << logs();
  EXPECT_EQ(tracker.keyframes_lost, 0) << logs();
  if (loss.every_third_keyframe) {
    EXPECT_GE(tracker.keyframes_requested, static_cast<std::int64_t>(relayed.dropped.size()));
    EXPECT_GE(relayed.resent, static_cast<int>(relayed.dropped.size()));
  }
  for (int k = 0; k < cvo_lcm::status_t::NUM_BAD_KINDS; ++k) {
    // A lost keyframe's local graph may arrive before the keyframe is recovered: refused, sent again.
    if (k == cvo_lcm::status_t::BAD_UNKNOWN_KEYFRAME) continue;
    EXPECT_EQ(backend.bad_messages[k], 0) << "kind " << k;
  }
}

TEST(KeyframeTransport, ARelayThatLosesEveryThirdWholeKeyframeFiveTimesLeavesTheMapWhole) {
  if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
  expect_every_keyframe_arrives({.every_third_keyframe = true}, {"trackerd.keyframe_transport=whole"});
}

class KeyframeTransportLoss : public ::testing::TestWithParam<int> {};

TEST_P(KeyframeTransportLoss, EveryKeyframeInSlicesArrivesWhileItsTrackerRuns) {
  if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
  expect_every_keyframe_arrives({.percent = GetParam()}, {});
}

INSTANTIATE_TEST_SUITE_P(DatagramLoss, KeyframeTransportLoss, ::testing::Values(10, 30),
                         [](const auto& test) { return std::to_string(test.param) + "Percent"; });

}  // namespace
}  // namespace cvo::daemon
