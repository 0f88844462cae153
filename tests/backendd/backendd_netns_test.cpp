// cvo-backendd end to end over real LCM UDP multicast, fed the keyframes and local graphs of a
// real cvo-trackerd run on the embedded clip (recorded once through a file:// provider):
// - killed (SIGKILL) half-way and restarted, its final CVO_MAP still holds every keyframe
//   (session, id) sent, and the restart says it recovered them from its store;
// - a CVO_KEYFRAME that repeats an existing (session, id) with other content is refused and
//   counted (CVO_STATUS bad_messages[BAD_CONFLICT]), a byte-identical repeat is not stored twice,
//   and the daemon keeps running and using the messages after them; a store that holds a record
//   twice (written before the door) is replayed once;
// - its final map's keyframe poses are the ones `cvo-run --mode slam` gives on the same frames:
//   one back end (slam::Mapper) serves both;
// - a SIGTERM while records wait ends within backendd.stop_timeout_s, and the next start applies
//   what waited (it was in the store).
//
// Runs only inside tests/support/in-private-netns (CVO_PRIVATE_NETNS=1): lo alone, no packet can
// leave the host.
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/lcm/map_conversion.hpp"
#include "libcvo/store/keyframe_store.hpp"
#include "libcvo/store/message_door.hpp"
#include "tests/backendd/netns_support.hpp"
#include "tests/backendd/tracker_recording.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::Captured;
using cvo::testing::DaemonProcess;
using cvo::testing::KeyframeName;
using cvo::testing::kUrl;
using cvo::testing::LcmCapture;

const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";

using cvo::testing::Message;

class BackenddNetns : public ::testing::Test {
 protected:
  // The tracker's keyframes and local graphs on the clip, in the order it published them: made
  // once for every test of the suite.
  static void SetUpTestSuite() {
    if (!cvo::testing::udp_test_skip_reason().empty()) return;
    const cvo::test::TempDir dir("backendd_recording");
    // PNG, lossless: cvo-run's images exactly.
    messages_ = cvo::testing::tracker_recording(dir.path(), {"trackerd.keyframe_colour_encoding=png"});
  }

  void SetUp() override {
    if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
    ASSERT_GE(keyframes_in(messages_.begin(), messages_.end()).size(), 4u) << "the tracker made too few keyframes";
  }

  using Iterator = std::vector<Message>::const_iterator;
  static store::MessageKey keyframe_key(const Message& m) {
    const auto message =
        store::identify(store::RecordKind::kKeyframe, m.bytes.data(), m.bytes.size(), nullptr, nullptr);
    return message ? message->key : store::MessageKey{store::RecordKind::kKeyframe, -1, -1};
  }
  static std::set<KeyframeName> keyframes_in(Iterator begin, Iterator end) {
    std::set<KeyframeName> names;
    for (auto it = begin; it != end; ++it)
      if (it->channel == "CVO_KEYFRAME") names.emplace(keyframe_key(*it).session, keyframe_key(*it).id);
    return names;
  }

  // Publishes messages as a tracker would; 10 Hz by default, so that nothing overflows a socket.
  static void send(Iterator begin, Iterator end, std::chrono::milliseconds pause = 100ms) {
    ::lcm::LCM lcm(kUrl);
    for (auto it = begin; it != end; ++it) {
      lcm.publish(it->channel, it->bytes.data(), static_cast<unsigned int>(it->bytes.size()));
      std::this_thread::sleep_for(pause);
    }
  }

  // Starts cvo-backendd (with `settings`, each a --set) and waits for its first CVO_STATUS: from
  // then on it receives.
  static std::unique_ptr<DaemonProcess> start(LcmCapture& capture, const fs::path& store, const fs::path& stderr_file,
                                              const std::vector<std::string>& settings = {}) {
    auto backendd = cvo::testing::start_backendd(store, stderr_file, settings);
    const int pid = backendd->pid();
    EXPECT_TRUE(capture.wait_until([&](const Captured& c) { return c.status_from(pid); }, 60s))
        << "no CVO_STATUS from cvo-backendd\n"
        << cvo::testing::slurp(stderr_file);
    return backendd;
  }

  // SIGTERM: exit status 0, and the final CVO_STATUS (after the final map) received.
  static void stop(DaemonProcess& backendd, LcmCapture& capture, const fs::path& stderr_file) {
    const auto code = cvo::testing::stop(backendd, 120s);
    ASSERT_TRUE(code) << "cvo-backendd did not stop on SIGTERM\n" << cvo::testing::slurp(stderr_file);
    EXPECT_EQ(*code, 0) << cvo::testing::slurp(stderr_file);
    const int pid = backendd.pid();
    const auto stopping = [&](const Captured& c) { return c.status_from(pid, +cvo_lcm::status_t::STATE_STOPPING); };
    EXPECT_TRUE(capture.wait_until(stopping, 30s)) << "no final CVO_STATUS";
  }

  // Just after the keyframe nearest the middle: the messages before it are in the store once
  // the back end's map holds that keyframe (one socket, in order, stored before used).
  static Iterator middle() {
    auto it = messages_.cbegin() + static_cast<std::ptrdiff_t>(messages_.size() / 2);
    while (it != messages_.cend() && it->channel != "CVO_KEYFRAME") ++it;
    return it == messages_.cend() ? it : it + 1;
  }

  static std::vector<Message> messages_;
};

std::vector<Message> BackenddNetns::messages_;

TEST_F(BackenddNetns, KilledAndRestartedMidReplayLosesNoKeyframe) {
  cvo::test::TempDir dir;
  const auto store = dir.path() / "state" / "keyframes.store";
  const auto half = middle();
  LcmCapture capture(dir.path() / "maps.lcmlog");
  ASSERT_TRUE(capture.good());
  {
    const auto err = dir.path() / "backendd1.txt";
    auto backendd = start(capture, store, err);
    send(messages_.begin(), half);
    // Received (the map holds them), then killed with no chance to flush anything.
    const auto first = keyframes_in(messages_.begin(), half);
    EXPECT_TRUE(capture.wait_until([&](const Captured& c) { return c.map_holds(first); }, 120s))
        << cvo::testing::slurp(err);
    ASSERT_TRUE(backendd->running()) << cvo::testing::slurp(err);
    backendd->signal(SIGKILL);
    backendd->wait_for(5s);
  }
  const auto err = dir.path() / "backendd2.txt";
  auto backendd = start(capture, store, err);
  send(half, messages_.end());
  stop(*backendd, capture, err);
  const auto log = cvo::testing::slurp(err);
  std::smatch recovered;
  ASSERT_TRUE(std::regex_search(log, recovered, std::regex("\\((\\d+) records recovered\\)"))) << log;
  EXPECT_EQ(std::stoul(recovered[1]), static_cast<unsigned long>(half - messages_.begin()))
      << "the restart found every record of the first half in its store";

  const Captured captured = capture.snapshot();
  ASSERT_TRUE(captured.map) << log;
  const auto all = keyframes_in(messages_.begin(), messages_.end());
  EXPECT_TRUE(captured.map_holds(all)) << log;
  EXPECT_EQ(captured.map->keyframes.size(), all.size());
  ASSERT_FALSE(captured.backend_statuses.empty());
  EXPECT_EQ(captured.backend_statuses.back().session, 0) << "the back end is no tracker session";
}

TEST_F(BackenddNetns, AKeyframeRepeatedWithOtherContentIsRefusedAndCounted) {
  cvo::test::TempDir dir;
  const auto store = dir.path() / "keyframes.store";
  const auto half = middle();
  // The second keyframe, once as it was and once re-encoded with its pose moved by 5 cm.
  const auto is_keyframe = [](const Message& m) { return m.channel == "CVO_KEYFRAME"; };
  const auto kf = std::find_if(std::find_if(messages_.cbegin(), half, is_keyframe) + 1, half, is_keyframe);
  ASSERT_NE(kf, half);
  auto changed = lcm::decode<cvo_lcm::keyframe_t>(kf->bytes.data(), static_cast<int>(kf->bytes.size()), nullptr);
  ASSERT_TRUE(changed);
  changed->pose.position[0] += 0.05;
  Message conflicting{"CVO_KEYFRAME", std::vector<std::uint8_t>(static_cast<std::size_t>(changed->getEncodedSize()))};
  changed->encode(conflicting.bytes.data(), 0, static_cast<int>(conflicting.bytes.size()));
  const std::vector<Message> repeats{*kf, conflicting};

  LcmCapture capture(dir.path() / "maps.lcmlog");
  ASSERT_TRUE(capture.good());
  const auto err = dir.path() / "backendd.txt";
  {
    auto backendd = start(capture, store, err);
    send(messages_.begin(), half);
    send(repeats.begin(), repeats.end());
    send(half, messages_.end());  // used after the refusal
    const auto all = keyframes_in(messages_.begin(), messages_.end());
    EXPECT_TRUE(capture.wait_until([&](const Captured& c) { return c.map_holds(all); }, 120s))
        << cvo::testing::slurp(err);
    ASSERT_TRUE(backendd->running()) << cvo::testing::slurp(err);
    stop(*backendd, capture, err);
  }
  const auto log = cvo::testing::slurp(err);
  const auto status = capture.snapshot().backend_statuses.back();
  EXPECT_EQ(status.bad_messages[cvo_lcm::status_t::BAD_CONFLICT], 1) << log;
  for (int k = 0; k < cvo_lcm::status_t::BAD_CONFLICT; ++k) EXPECT_EQ(status.bad_messages[k], 0) << "kind " << k;
  const auto name = store::describe(keyframe_key(*kf));
  EXPECT_NE(log.find(name + " repeats an existing one with other content: refused"), std::string::npos) << log;

  // Every message once in the store: neither the repeat nor the conflicting one.
  std::vector<store::StoredRecord> records;
  std::string warning;
  {
    store::KeyframeStore reopened(store, records, warning);
    EXPECT_EQ(reopened.records(), messages_.size());
    reopened.append(store::RecordKind::kKeyframe, kf->bytes);  // as a store written before the door could hold it
  }

  // The store with the repeat is replayed once: the same map, the repeat skipped with a note.
  const auto err2 = dir.path() / "backendd2.txt";
  auto backendd = start(capture, store, err2);
  stop(*backendd, capture, err2);
  const auto log2 = cvo::testing::slurp(err2);
  EXPECT_NE(log2.find("stored record skipped: " + name + " is in the store twice"), std::string::npos) << log2;
  EXPECT_EQ(log2.find("not applied"), std::string::npos) << log2;
  const Captured captured = capture.snapshot();
  ASSERT_TRUE(captured.map);
  EXPECT_EQ(captured.map->keyframes.size(), keyframes_in(messages_.begin(), messages_.end()).size());
}

// A back end slower than its tracker: room for one record in its queue, the messages ten times
// faster than it applies them, and no tracker left to ask again (it exited after its last frame,
// as one with --exit-on-eof does). What finds the queue full waits in the store and is applied
// after the rest: the final map holds every keyframe and local graph, nothing refused or lost.
TEST_F(BackenddNetns, ABackEndSlowerThanItsTrackerLosesNoKeyframe) {
  cvo::test::TempDir dir;
  LcmCapture capture(dir.path() / "maps.lcmlog");
  ASSERT_TRUE(capture.good());
  const auto err = dir.path() / "backendd.txt";
  auto backendd = start(capture, dir.path() / "keyframes.store", err, {"backendd.queue_max=1"});
  send(messages_.begin(), messages_.end(), 10ms);
  stop(*backendd, capture, err);
  const auto log = cvo::testing::slurp(err);

  const Captured captured = capture.snapshot();
  ASSERT_TRUE(captured.map) << log;
  const auto all = keyframes_in(messages_.begin(), messages_.end());
  EXPECT_TRUE(captured.map_holds(all)) << log;
  EXPECT_EQ(captured.map->keyframes.size(), all.size()) << log;
  std::smatch graphs;
  ASSERT_TRUE(std::regex_search(log, graphs, std::regex("; (\\d+) local graphs;"))) << log;
  EXPECT_EQ(std::stoul(graphs[1]), all.size()) << log;
  ASSERT_FALSE(captured.backend_statuses.empty());
  const auto& status = captured.backend_statuses.back();
  EXPECT_EQ(status.queue_drops, 0) << log;
  EXPECT_EQ(status.keyframes_lost, 0) << log;
  // It did have to wait: the queue was full for most of the burst.
  EXPECT_NE(log.find("waited in the store"), std::string::npos) << log;
}

// A SIGTERM while records wait ends within backendd.stop_timeout_s (here 0: nothing more is applied,
// the final optimisation is skipped), inside the unit's TimeoutStopSec (30 s) that systemd gives
// before SIGKILL; what waited is in the store, and the next start applies it all.
TEST_F(BackenddNetns, AStopEndsInTimeAndTheNextStartAppliesWhatWaited) {
  cvo::test::TempDir dir;
  const auto store = dir.path() / "keyframes.store";
  const auto all = keyframes_in(messages_.begin(), messages_.end());
  {
    LcmCapture capture(dir.path() / "first.lcmlog");
    ASSERT_TRUE(capture.good());
    const auto err = dir.path() / "first.txt";
    auto backendd = start(capture, store, err, {"backendd.queue_max=1", "backendd.stop_timeout_s=0"});
    send(messages_.begin(), messages_.end(), 10ms);
    const auto code = cvo::testing::stop(*backendd, 30s);  // the unit's TimeoutStopSec
    ASSERT_TRUE(code) << "cvo-backendd did not stop within TimeoutStopSec\n" << cvo::testing::slurp(err);
    EXPECT_EQ(*code, 0);
    const auto log = cvo::testing::slurp(err);
    EXPECT_TRUE(std::regex_search(log, std::regex("\\d+ records not applied within backendd.stop_timeout_s"))) << log;
    EXPECT_NE(log.find("final optimisation skipped"), std::string::npos) << log;
    const Captured captured = capture.snapshot();
    ASSERT_TRUE(captured.map) << "the final CVO_MAP goes out in any case\n" << log;
    EXPECT_LT(captured.map->keyframes.size(), all.size()) << log;
  }
  LcmCapture capture(dir.path() / "second.lcmlog");
  ASSERT_TRUE(capture.good());
  const auto err = dir.path() / "second.txt";
  auto backendd = start(capture, store, err);
  stop(*backendd, capture, err);
  const auto log = cvo::testing::slurp(err);
  const Captured captured = capture.snapshot();
  ASSERT_TRUE(captured.map) << log;
  EXPECT_TRUE(captured.map_holds(all)) << log;
  EXPECT_EQ(captured.map->keyframes.size(), all.size()) << log;
  EXPECT_NE(log.find("final optimisation: cost"), std::string::npos) << log;
}

// cvo-trackerd --deterministic and cvo-run track the same frames with the same KF-CVO; the daemon's
// back end and cvo-run's are one slam::Mapper fed the same keyframes (the tracker's own clouds)
// and local graphs in the same order, so the final maps agree keyframe by keyframe (to the
// trajectory file's nine decimals).
TEST_F(BackenddNetns, GivesTheKeyframePosesCvoRunGivesOnTheSameFrames) {
  cvo::test::TempDir dir;
  LcmCapture capture(dir.path() / "maps.lcmlog");
  ASSERT_TRUE(capture.good());
  const auto err = dir.path() / "backendd.txt";
  {
    auto backendd = start(capture, dir.path() / "keyframes.store", err);
    send(messages_.begin(), messages_.end());
    const auto all = keyframes_in(messages_.begin(), messages_.end());
    EXPECT_TRUE(capture.wait_until([&](const Captured& c) { return c.map_holds(all); }, 120s))
        << cvo::testing::slurp(err);
    stop(*backendd, capture, err);
  }
  const auto captured = capture.snapshot();
  ASSERT_TRUE(captured.map);
  std::string error;
  const auto map = lcm::from_message(*captured.map, &error);
  ASSERT_TRUE(map) << error;

  const auto traj = dir.path() / "cvo-run.txt";
  const auto run = cvo::testing::run_tool(
      "cvo-run", cvo::testing::quoted(kClip) + " --mode slam --out " + cvo::testing::quoted(traj), dir.path());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const core::Trajectory frames = io::read_tum_trajectory(traj);
  ASSERT_GE(map->keyframes.size(), 4u);
  for (const auto& k : map->keyframes) {
    const auto at = std::find_if(frames.begin(), frames.end(), [&](const core::StampedPose& p) {
      return std::abs(p.timestamp - k.timestamp) < 1e-5;
    });
    ASSERT_NE(at, frames.end()) << "keyframe " << k.id << " at " << k.timestamp << " is no frame of cvo-run's";
    EXPECT_LT((at->pose.translation() - k.pose.translation()).norm(), 1e-6) << "keyframe " << k.id;
    EXPECT_LT(at->pose.rotation().angularDistance(k.pose.rotation()), 1e-6) << "keyframe " << k.id;
  }
}

}  // namespace
}  // namespace cvo::daemon
