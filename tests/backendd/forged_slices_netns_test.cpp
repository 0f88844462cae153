// Issue 48: slices that cannot pre-empt, through the real daemons on an open bus. A forger in this
// test process publishes on the daemons' group:
// - one forged first slice for each of a live tracker session's next keyframe names (and their
//   local graphs'), again with every CVO_POSE it hears (~300 slices a second): before, those names
//   were held by the forgery and the genuine slices refused as conflicts (11 of 27 keyframes never
//   stored); now every keyframe the tracker made reaches the map and none is lost;
// - 3 000 random slices a second of sessions no tracker speaks for: before, none was counted
//   refused, keyframe requests went to sessions that do not exist and keyframes_lost ran to
//   millions; now they are counted (BAD_UNKNOWN_KEYFRAME), nothing is asked for or lost, and the
//   back end's memory stays within the strangers' room.
//
// Runs only inside tests/support/in-private-netns (CVO_PRIVATE_NETNS=1): lo alone.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/keyframe_chunk_t.hpp"
#include "cvo_lcm/keyframe_request_t.hpp"
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
using Chunk = cvo_lcm::keyframe_chunk_t;
using cvo::testing::Captured;
using cvo::testing::KeyframeName;
using cvo::testing::LcmCapture;

const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";

// A first slice of a message that is not: a size and CRC the genuine one will not have.
Chunk forged_slice(std::int64_t session, std::int64_t id, std::int8_t message, std::uint32_t crc) {
  Chunk c{};
  c.version = Chunk::SCHEMA_VERSION;
  c.session = session;
  c.id = id;
  c.message = message;
  c.message_size = 300 * Chunk::MAX_DATA;
  c.message_crc = static_cast<std::int32_t>(crc);
  c.index = 0;
  c.data.assign(Chunk::MAX_DATA, 0xee);
  c.data_size = Chunk::MAX_DATA;
  return c;
}

// Hears CVO_POSE and CVO_KEYFRAME_REQUEST on the daemons' bus; on each pose, forges the first
// slices of the session's next kAhead keyframes and local graphs.
class Forger {
 public:
  static constexpr std::int64_t kAhead = 5;
  explicit Forger(bool pre_empt) : pre_empt_(pre_empt), lcm_(cvo::testing::kUrl) {
    lcm_.subscribe("CVO_POSE", &Forger::pose, this);
    lcm_.subscribe("CVO_KEYFRAME_REQUEST", &Forger::request, this);
    thread_ = std::thread([this] {
      while (!stop_) lcm_.handleTimeout(20);
    });
  }
  ~Forger() {
    stop_ = true;
    thread_.join();
  }
  Forger(const Forger&) = delete;
  Forger& operator=(const Forger&) = delete;

  [[nodiscard]] bool good() { return lcm_.good(); }
  [[nodiscard]] int requests() const { return requests_; }
  [[nodiscard]] std::int64_t forged() const { return forged_; }
  /// Every keyframe of the tracker's session its poses named (ids from 0).
  std::set<KeyframeName> made() {
    const std::lock_guard lock(mutex_);
    return made_;
  }

  /// `per_second` random slices of random sessions for `how_long` (on the calling thread).
  void flood(int per_second, std::chrono::milliseconds how_long) {
    ::lcm::LCM lcm(cvo::testing::kUrl);
    std::mt19937_64 random(48);
    const auto start = std::chrono::steady_clock::now();
    for (std::int64_t n = 0; std::chrono::steady_clock::now() - start < how_long; ++n) {
      Chunk c = forged_slice(static_cast<std::int64_t>(random()), static_cast<std::int64_t>(random() % 100000),
                             static_cast<std::int8_t>(random() % 2), static_cast<std::uint32_t>(random()));
      c.index = static_cast<std::int32_t>(random() % 300);
      lcm.publish("CVO_KEYFRAME_CHUNK", &c);
      ++forged_;
      std::this_thread::sleep_until(start + n * std::chrono::microseconds(1'000'000 / per_second));
    }
  }

 private:
  void pose(const ::lcm::ReceiveBuffer* buffer, const std::string&) {
    const auto p = lcm::decode<cvo_lcm::pose_t>(buffer->data, static_cast<int>(buffer->data_size), nullptr);
    if (!p) return;
    {
      const std::lock_guard lock(mutex_);
      for (std::int64_t id = 0; id <= p->keyframe_id; ++id) made_.emplace(p->session, id);
    }
    if (!pre_empt_) return;
    for (std::int64_t id = p->keyframe_id + 1; id <= p->keyframe_id + kAhead; ++id)
      for (const std::int8_t message : {Chunk::KEYFRAME, Chunk::LOCAL_GRAPH}) {
        const auto c = forged_slice(p->session, id, message, 0xf0f0f0f0U ^ static_cast<std::uint32_t>(id));
        lcm_.publish("CVO_KEYFRAME_CHUNK", &c);
        ++forged_;
      }
  }
  void request(const ::lcm::ReceiveBuffer*, const std::string&) { ++requests_; }

  const bool pre_empt_;
  ::lcm::LCM lcm_;
  std::mutex mutex_;
  std::set<KeyframeName> made_;  // under mutex_
  std::atomic<int> requests_{0};
  std::atomic<std::int64_t> forged_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

TEST(ForgedSlices, ALiveSessionsNextKeyframeNamesPreEmptedByForgedFirstSlicesStillAllReachTheStore) {
  if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
  cvo::test::TempDir dir;
  LcmCapture capture(dir.path() / "maps.lcmlog");
  ASSERT_TRUE(capture.good());
  Forger forger(/*pre_empt=*/true);
  ASSERT_TRUE(forger.good());
  const auto backend_err = dir.path() / "backendd.txt", tracker_err = dir.path() / "trackerd.txt";
  auto backendd = cvo::testing::start_backendd(dir.path() / "keyframes.store", backend_err);
  const int backend_pid = backendd->pid();
  ASSERT_TRUE(capture.wait_until([&](const Captured& c) { return c.status_from(backend_pid); }, 60s))
      << cvo::testing::slurp(backend_err);
  auto trackerd = cvo::testing::start_trackerd(kClip, tracker_err, /*exit_at_end=*/false);
  const auto logs = [&] { return cvo::testing::slurp(tracker_err) + cvo::testing::slurp(backend_err); };

  ASSERT_TRUE(capture.wait_until(
      [](const Captured& c) { return !c.last_frame.empty() && c.last_frame.begin()->second == 49; }, 120s))
      << logs();
  const auto made = forger.made();
  ASSERT_GE(made.size(), 6u);
  EXPECT_TRUE(capture.wait_until([&](const Captured& c) { return c.map_holds(made); }, 60s))
      << "not every keyframe reached the map while the tracker runs\n"
      << logs();
  EXPECT_EQ(cvo::testing::stop(trackerd, 60s).value_or(-9), 0) << logs();
  EXPECT_EQ(cvo::testing::stop(*backendd, 120s).value_or(-9), 0) << logs();
  ASSERT_TRUE(capture.wait_until(
      [&](const Captured& c) { return c.status_from(backend_pid, +cvo_lcm::status_t::STATE_STOPPING); }, 30s));
  const Captured captured = capture.snapshot();
  EXPECT_TRUE(captured.map_holds(made)) << "the final map\n" << logs();
  const auto& status = captured.backend_statuses.back();
  std::cout << "keyframes made " << made.size() << ", forged slices " << forger.forged() << ", refused as conflicts "
            << status.bad_messages[cvo_lcm::status_t::BAD_CONFLICT] << ", keyframes lost " << status.keyframes_lost
            << std::endl;
  EXPECT_EQ(status.keyframes_lost, 0) << logs();
}

TEST(ForgedSlices, ARandomSliceFloodIsCountedRefusedAsksForNothingAndLosesNoKeyframe) {
  if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
  cvo::test::TempDir dir;
  LcmCapture capture(dir.path() / "maps.lcmlog");
  ASSERT_TRUE(capture.good());
  Forger forger(/*pre_empt=*/false);
  ASSERT_TRUE(forger.good());
  const auto backend_err = dir.path() / "backendd.txt";
  auto backendd = cvo::testing::start_backendd(dir.path() / "keyframes.store", backend_err);
  const int backend_pid = backendd->pid();
  ASSERT_TRUE(capture.wait_until([&](const Captured& c) { return c.status_from(backend_pid); }, 60s))
      << cvo::testing::slurp(backend_err);
  const auto rss_before = capture.snapshot().backend_statuses.back().rss_bytes;

  forger.flood(3000, 4000ms);
  std::this_thread::sleep_for(3s);  // the requests would have gone by now (keyframe_gaps.hpp: 0.5 s)
  EXPECT_EQ(cvo::testing::stop(*backendd, 120s).value_or(-9), 0) << cvo::testing::slurp(backend_err);
  ASSERT_TRUE(capture.wait_until(
      [&](const Captured& c) { return c.status_from(backend_pid, +cvo_lcm::status_t::STATE_STOPPING); }, 30s));
  const Captured captured = capture.snapshot();
  const auto& status = captured.backend_statuses.back();
  std::int64_t rss_peak = 0;
  for (const auto& s : captured.backend_statuses) rss_peak = std::max(rss_peak, s.rss_bytes);
  const auto refused = status.bad_messages[cvo_lcm::status_t::BAD_UNKNOWN_KEYFRAME];
  std::cout << "forged slices " << forger.forged() << ", refused " << refused << ", requests " << forger.requests()
            << ", keyframes requested " << status.keyframes_requested << ", lost " << status.keyframes_lost << ", RSS "
            << rss_before / (1 << 20) << " MiB before, " << rss_peak / (1 << 20) << " MiB at most" << std::endl;
  EXPECT_GE(refused, forger.forged() * 9 / 10) << "what LCM delivered, at most the strangers' room held";
  EXPECT_EQ(forger.requests(), 0);
  EXPECT_EQ(status.keyframes_requested, 0);
  EXPECT_EQ(status.keyframes_lost, 0);
  EXPECT_LE(rss_peak - rss_before, std::int64_t{12} << 20) << "the strangers' room is a few dozen slices";
}

}  // namespace
}  // namespace cvo::daemon
