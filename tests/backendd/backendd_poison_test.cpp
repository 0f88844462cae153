// cvo-backendd fed a poison recording: a real tracker's keyframes and local graphs with hostile
// messages among them (a keyframe repeating an id with other content, a local graph for a keyframe
// that never came, a NaN pose, an indefinite information matrix, another schema version, a
// truncated message, another message type). Read from a file:// log with --exit-on-eof, it keeps
// going, counts each refusal by kind in CVO_STATUS, stores none of them, and its final map is the
// one the clean recording gives: every good message was used.
//
// No network: the input is a log and the output another (file:// providers both ways).
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/local_graph_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/store/keyframe_store.hpp"
#include "tests/backendd/tracker_recording.hpp"
#include "tests/support/cli_contract.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/lcm_log.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::DaemonProcess;

using Event = cvo::testing::Message;

template <class T>
Event event(const std::string& channel, const T& message) {
  Event e{channel, std::vector<std::uint8_t>(static_cast<std::size_t>(message.getEncodedSize()))};
  message.encode(e.bytes.data(), 0, static_cast<int>(e.bytes.size()));
  return e;
}

template <class T>
T decoded(const Event& e) {
  auto m = lcm::decode<T>(e.bytes.data(), static_cast<int>(e.bytes.size()), nullptr);
  EXPECT_TRUE(m) << e.channel;
  return m.value_or(T{});
}

// Where the poison goes into the recording: a third of the way.
std::size_t poison_at(const std::vector<Event>& good) { return good.size() / 3; }

// One of each kind of poison, made from the recording's own messages. The conflicting keyframe
// repeats one sent before the poison; the indefinite graph is the twin of one sent after it (so
// the good one is new when it comes).
std::vector<std::pair<Event, int>> poison(const std::vector<Event>& good) {
  const auto first_of = [&](const std::string& channel, int skip, std::size_t from = 0) {
    for (std::size_t i = from; i < good.size(); ++i)
      if (good[i].channel == channel && skip-- == 0) return good[i];
    return Event{};
  };
  std::vector<std::pair<Event, int>> out;
  auto moved = decoded<cvo_lcm::keyframe_t>(first_of("CVO_KEYFRAME", 1));
  moved.pose.position[0] += 0.05;  // keyframe 1 again, elsewhere
  out.emplace_back(event("CVO_KEYFRAME", moved), cvo_lcm::status_t::BAD_CONFLICT);
  auto orphan = decoded<cvo_lcm::local_graph_t>(first_of("CVO_LOCAL_GRAPH", 0));
  orphan.keyframe_id = 999;  // no such keyframe
  out.emplace_back(event("CVO_LOCAL_GRAPH", orphan), cvo_lcm::status_t::BAD_UNKNOWN_KEYFRAME);
  auto nan = decoded<cvo_lcm::keyframe_t>(first_of("CVO_KEYFRAME", 0));
  nan.id = 1000;
  nan.pose.position[1] = std::numeric_limits<double>::quiet_NaN();
  out.emplace_back(event("CVO_KEYFRAME", nan), cvo_lcm::status_t::BAD_NOT_FINITE);
  auto indefinite = decoded<cvo_lcm::local_graph_t>(first_of("CVO_LOCAL_GRAPH", 0, poison_at(good)));
  indefinite.edges.front().information[0] = -1.0;  // a negative variance
  out.emplace_back(event("CVO_LOCAL_GRAPH", indefinite), cvo_lcm::status_t::BAD_INFORMATION);
  auto future = decoded<cvo_lcm::keyframe_t>(first_of("CVO_KEYFRAME", 0));
  future.id = 1001;
  future.version = cvo_lcm::keyframe_t::SCHEMA_VERSION + 1;
  out.emplace_back(event("CVO_KEYFRAME", future), cvo_lcm::status_t::BAD_VERSION);
  Event cut = first_of("CVO_KEYFRAME", 2);
  cut.bytes.resize(cut.bytes.size() / 2);
  out.emplace_back(cut, cvo_lcm::status_t::BAD_BODY);
  cvo_lcm::pose_t pose{};
  pose.version = cvo_lcm::pose_t::SCHEMA_VERSION;
  out.emplace_back(event("CVO_KEYFRAME", pose), cvo_lcm::status_t::BAD_FINGERPRINT);
  return out;
}

void write_log(const fs::path& file, const std::vector<Event>& good, const std::vector<std::pair<Event, int>>& bad) {
  ::lcm::LogFile log(file.string(), "w");
  std::int64_t t = 0;
  const auto write = [&](const Event& e) { cvo::testing::write_event(log, e.channel, e.bytes, t += 1000); };
  const std::size_t at = poison_at(good);
  for (std::size_t i = 0; i < good.size(); ++i) {
    if (i == at)
      for (const auto& [e, kind] : bad) write(e);
    write(good[i]);
  }
}

struct Outcome {
  int exit_code = -1;
  std::string log;
  cvo::testing::PublishedLog published;
  std::uint64_t records = 0;
};

Outcome run_backendd(const fs::path& dir, const std::string& name, const fs::path& input,
                     const std::vector<std::string>& settings = {}) {
  const auto out = dir / (name + ".out.lcmlog");
  const auto store = dir / (name + ".store");
  std::vector<std::string> arguments{"--lcm-url",     "file://" + input.string() + "?speed=0",
                                     "--publish-url", "file://" + out.string() + "?mode=w",
                                     "--store",       store.string(),
                                     "--exit-on-eof"};
  for (const auto& s : settings) arguments.insert(arguments.end(), {"--set", s});
  DaemonProcess backendd(fs::path(CVO_TOOLS_DIR) / "cvo-backendd", arguments, dir / (name + ".txt"));
  Outcome o;
  o.exit_code = backendd.wait_for(300s).value_or(-9);
  o.log = cvo::testing::slurp(dir / (name + ".txt"));
  o.published = cvo::testing::read_published(out);
  std::vector<store::StoredRecord> records;
  std::string warning;
  o.records = store::KeyframeStore(store, records, warning).records();
  return o;
}

TEST(BackenddPoison, EveryRefusalIsCountedByKindAndEveryGoodMessageIsUsed) {
  const cvo::test::TempDir dir("backendd_poison");
  const auto good = cvo::testing::tracker_recording(dir.path());
  ASSERT_GE(good.size(), 8u);
  const auto bad = poison(good);
  write_log(dir.path() / "clean.lcmlog", good, {});
  write_log(dir.path() / "poison.lcmlog", good, bad);

  const Outcome clean = run_backendd(dir.path(), "clean", dir.path() / "clean.lcmlog");
  const Outcome poisoned = run_backendd(dir.path(), "poisoned", dir.path() / "poison.lcmlog");
  ASSERT_EQ(clean.exit_code, 0) << clean.log;
  ASSERT_EQ(poisoned.exit_code, 0) << "the end of the log is a clean end\n" << poisoned.log;

  ASSERT_FALSE(poisoned.published.statuses.empty()) << poisoned.log;
  const auto& status = poisoned.published.statuses.back();
  EXPECT_EQ(status.state, +cvo_lcm::status_t::STATE_STOPPING);
  int expected[cvo_lcm::status_t::NUM_BAD_KINDS] = {};
  for (const auto& [e, kind] : bad) ++expected[kind];
  for (int k = 0; k < cvo_lcm::status_t::NUM_BAD_KINDS; ++k)
    EXPECT_EQ(status.bad_messages[k], expected[k]) << "refusals of kind " << k << "\n" << poisoned.log;
  for (const auto& s : clean.published.statuses)
    for (int k = 0; k < cvo_lcm::status_t::NUM_BAD_KINDS; ++k) EXPECT_EQ(s.bad_messages[k], 0);

  // Nothing refused was stored; every good message was, and was used: the same final map.
  EXPECT_EQ(poisoned.records, good.size());
  EXPECT_EQ(clean.records, good.size());
  ASSERT_FALSE(clean.published.maps.empty());
  ASSERT_FALSE(poisoned.published.maps.empty());
  const auto& a = clean.published.maps.back();
  const auto& b = poisoned.published.maps.back();
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  for (std::size_t i = 0; i < a.keyframes.size(); ++i) {
    EXPECT_EQ(a.keyframes[i].id, b.keyframes[i].id);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(a.keyframes[i].pose.position[c], b.keyframes[i].pose.position[c], 1e-9) << "keyframe " << i;
  }
  EXPECT_EQ(a.num_loops, b.num_loops);
}

// Issue 26: every new (session, id) was stored, so made-up sessions could grow the store without
// end. Now a session stores at most backendd.max_records_per_session records and a sender (on an
// open bus: everyone) at most backendd.max_records_per_sender; past either a record is refused as
// BAD_QUOTA, named in the notes, and not stored. Here the real session fits its bound exactly; a
// made-up session (copies of a real keyframe) passes it by two, a second one finds the sender's
// bound after one.
TEST(BackenddPoison, RecordsPastASessionsOrASendersBoundAreRefusedAsQuota) {
  const cvo::test::TempDir dir("backendd_quota");
  const auto good = cvo::testing::tracker_recording(dir.path());
  const std::size_t P = good.size();
  ASSERT_GE(P, 8u);
  auto copy = decoded<cvo_lcm::keyframe_t>(
      *std::find_if(good.begin(), good.end(), [](const Event& e) { return e.channel == "CVO_KEYFRAME"; }));
  std::vector<std::pair<Event, int>> forged;
  for (std::size_t id = 0; id < P + 2; ++id) {
    copy.session = 0x0bad'0000'0001;
    copy.id = static_cast<std::int64_t>(id);
    forged.emplace_back(event("CVO_KEYFRAME", copy), id < P ? -1 : +cvo_lcm::status_t::BAD_QUOTA);
  }
  for (std::size_t id = 0; id < 3; ++id) {
    copy.session = 0x0bad'0000'0002;
    copy.id = static_cast<std::int64_t>(id);
    forged.emplace_back(event("CVO_KEYFRAME", copy), id < 1 ? -1 : +cvo_lcm::status_t::BAD_QUOTA);
  }
  {
    ::lcm::LogFile log((dir.path() / "quota.lcmlog").string(), "w");
    std::int64_t t = 0;
    for (const auto& e : good) cvo::testing::write_event(log, e.channel, e.bytes, t += 1000);
    for (const auto& [e, kind] : forged) cvo::testing::write_event(log, e.channel, e.bytes, t += 1000);
  }
  const Outcome o = run_backendd(dir.path(), "quota", dir.path() / "quota.lcmlog",
                                 {"backendd.max_records_per_session=" + std::to_string(P),
                                  "backendd.max_records_per_sender=" + std::to_string(2 * P + 1)});
  ASSERT_EQ(o.exit_code, 0) << o.log;
  ASSERT_FALSE(o.published.statuses.empty()) << o.log;
  EXPECT_EQ(o.published.statuses.back().bad_messages[cvo_lcm::status_t::BAD_QUOTA], 4) << o.log;
  EXPECT_EQ(o.records, 2 * P + 1) << "the refused ones are not stored";
  EXPECT_NE(o.log.find("(backendd.max_records_per_session)"), std::string::npos) << o.log;
  // (The sender's refusals are counted above; notes of one kind are rate-limited, the first said.)
  ASSERT_FALSE(o.published.maps.empty());
  std::size_t genuine = 0;
  for (const auto& k : o.published.maps.back().keyframes)
    genuine += k.session == decoded<cvo_lcm::keyframe_t>(good.front()).session ? 1 : 0;
  EXPECT_EQ(genuine * 2, P) << "every genuine keyframe reached the map";
}

// SIGHUP is a stop like SIGTERM: the queue is drained, the final optimisation runs and the final
// map goes out, exit 0 (its default action would kill the daemon with 129 and no final map).
TEST(Backendd, SigHupStopsCleanlyWithTheFinalMap) {
  const cvo::test::TempDir dir("backendd_sighup");
  const auto good = cvo::testing::tracker_recording(dir.path());
  write_log(dir.path() / "in.lcmlog", good, {});
  const auto out = dir.path() / "out.lcmlog";
  const auto err_file = dir.path() / "err.txt";
  DaemonProcess backendd(fs::path(CVO_TOOLS_DIR) / "cvo-backendd",
                         {"--lcm-url", "file://" + (dir.path() / "in.lcmlog").string() + "?speed=0", "--publish-url",
                          "file://" + out.string() + "?mode=w", "--store", (dir.path() / "s.store").string()},
                         err_file);
  cvo::testing::wait_for_text(err_file, "end of", 300s);  // the source was read to its end
  ASSERT_TRUE(backendd.running()) << cvo::testing::slurp(err_file);
  backendd.signal(SIGHUP);
  const auto code = backendd.wait_for(120s);
  ASSERT_TRUE(code) << "still running after SIGHUP";
  const auto err = cvo::testing::slurp(err_file);
  EXPECT_EQ(*code, 0) << err;
  EXPECT_NE(err.find("stopping on SIGHUP"), std::string::npos) << err;
  const auto published = cvo::testing::read_published(out);
  ASSERT_FALSE(published.maps.empty()) << err;
  ASSERT_FALSE(published.statuses.empty());
  EXPECT_EQ(published.statuses.back().state, +cvo_lcm::status_t::STATE_STOPPING);
  const auto keyframes =
      std::count_if(good.begin(), good.end(), [](const Event& e) { return e.channel == "CVO_KEYFRAME"; });
  EXPECT_EQ(static_cast<std::ptrdiff_t>(published.maps.back().keyframes.size()), keyframes)
      << "the final map has them all";
}

// A keyframe as schema version 3 wrote it (before readout_s): v3's fingerprint (its lcm-gen
// header's getHash()), version 3, and the body without the 8 bytes of readout_s.
std::vector<std::uint8_t> as_version_3(const Event& keyframe) {
  static constexpr std::uint8_t kFingerprintV3[8] = {0x70, 0xd4, 0xc7, 0xdf, 0xf7, 0xc2, 0x1a, 0xde};
  constexpr std::size_t kReadoutAt = 8 + 180;  // fingerprint, then the body offset (wire_layout.cpp)
  std::vector<std::uint8_t> bytes = keyframe.bytes;
  bytes.erase(bytes.begin() + kReadoutAt, bytes.begin() + kReadoutAt + 8);
  std::copy(std::begin(kFingerprintV3), std::end(kFingerprintV3), bytes.begin());
  bytes[11] = 3;  // the big-endian version field
  return bytes;
}

// A store written by an older build holds keyframes of an older schema: each is skipped at the
// start with a message saying so, and every record of the current schema is used.
TEST(BackenddPoison, StoredRecordsOfAnOlderSchemaAreSkippedWithAMessage) {
  const cvo::test::TempDir dir("backendd_poison");
  const auto good = cvo::testing::tracker_recording(dir.path());
  ASSERT_GE(good.size(), 8u);
  std::size_t keyframes = 0;
  {
    std::vector<store::StoredRecord> none;
    std::string warning;
    store::KeyframeStore store(dir.path() / "old.store", none, warning);
    for (const auto& e : good) {
      const bool keyframe = e.channel == "CVO_KEYFRAME";
      keyframes += keyframe;
      if (keyframe && keyframes == 2) {  // the old record first, as an older build stored it
        ASSERT_EQ(store.append(store::RecordKind::kKeyframe, as_version_3(e)), store::Appended::kStored);
      }
      store.append(keyframe ? store::RecordKind::kKeyframe : store::RecordKind::kLocalGraph, e.bytes);
    }
  }
  {  // an input with nothing for the back end (LCM cannot open a log without an event)
    ::lcm::LogFile log((dir.path() / "idle.lcmlog").string(), "w");
    cvo::testing::write_event(log, "ANOTHER_CHANNEL", {0}, 1000);
  }
  const Outcome o = run_backendd(dir.path(), "old", dir.path() / "idle.lcmlog");
  ASSERT_EQ(o.exit_code, 0) << o.log;
  EXPECT_NE(o.log.find("(" + std::to_string(good.size() + 1) + " records recovered)"), std::string::npos) << o.log;
  EXPECT_NE(o.log.find("stored record skipped: cvo_lcm.keyframe_t: wrong fingerprint"), std::string::npos) << o.log;
  EXPECT_NE(o.log.find("another schema version"), std::string::npos) << o.log;
  ASSERT_FALSE(o.published.maps.empty()) << o.log;
  EXPECT_EQ(o.published.maps.back().keyframes.size(), keyframes) << "every current record is used";
}

TEST(Backendd, HelpListsEveryOptionAndAnUnknownOneExitsTwoNamingIt) {
  cvo::test::TempDir dir;
  cvo::testing::expect_cli_contract(
      "cvo-backendd", "",
      {"--config", "--lcm-url", "--store", "--publish-url", "--exit-on-eof", "--set", "--print-config"}, dir.path());
}

TEST(Backendd, SetWithoutAnEqualsSignIsAUsageError) {
  cvo::test::TempDir dir;
  cvo::testing::expect_set_needs_key_equals_value("cvo-backendd", "--print-config", dir.path());
}

TEST(BackenddPoison, ExitOnEofNeedsALog) {
  const cvo::test::TempDir dir("backendd_poison");
  DaemonProcess backendd(
      fs::path(CVO_TOOLS_DIR) / "cvo-backendd",
      {"--lcm-url", "udpm://239.255.76.67:7667?ttl=0", "--store", (dir.path() / "s").string(), "--exit-on-eof"},
      dir.path() / "err.txt");
  EXPECT_EQ(backendd.wait_for(60s).value_or(-9), 1);
  EXPECT_NE(cvo::testing::slurp(dir.path() / "err.txt").find("backendd.exit_on_eof"), std::string::npos);
}

// The receiving provider is checked as the publishing one is, whether or not they are one.
TEST(BackenddPoison, AnUnopenableLcmUrlIsAnErrorNamingItWithOrWithoutAPublishUrl) {
  const cvo::test::TempDir dir("backendd_poison");
  for (const bool publish : {false, true}) {
    std::vector<std::string> args{"--lcm-url", "bogus://x", "--store", (dir.path() / "s").string()};
    if (publish)
      args.insert(args.end(), {"--publish-url", "file://" + (dir.path() / "out.lcmlog").string() + "?mode=w"});
    DaemonProcess backendd(fs::path(CVO_TOOLS_DIR) / "cvo-backendd", args, dir.path() / "err.txt");
    EXPECT_EQ(backendd.wait_for(60s).value_or(-9), 1) << "with --publish-url: " << publish;
    const auto err = cvo::testing::slurp(dir.path() / "err.txt");
    EXPECT_NE(err.find("backendd.lcm_url"), std::string::npos) << err;
    EXPECT_NE(err.find("bogus://x"), std::string::npos) << err;
  }
}

}  // namespace
}  // namespace cvo::daemon
