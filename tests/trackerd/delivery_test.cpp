// cvo-trackerd's delivery (daemon/trackerd/delivery.hpp), with its spool in a fresh folder and on a
// clock of its own: what is published is spooled, a keyframe is waited for once its local graph is
// out, what is sent again unasked, when a done publisher may exit (at once with no back end ever
// heard, else once all is acknowledged or the linger has passed), the closing note, what an earlier
// run left for the next to hand over, the spool's notes of drops and failed writes, and that an
// acknowledgement covers nothing beyond what was published.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "daemon/trackerd/delivery.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon::trackerd {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = Delivery::Clock;
using Bytes = std::vector<std::uint8_t>;
using Due = std::vector<std::pair<std::int64_t, std::int64_t>>;
using Key = std::tuple<std::int64_t, std::int64_t, bool>;  // session, id, graph

constexpr std::int64_t kSession = 0x5e5510'0000'0001;
constexpr std::int64_t kOther = 0x5e5510'0000'0002;
constexpr std::uintmax_t kRoom = 1 << 20;
constexpr double kLinger = 10.0;
const Clock::time_point t0{};
const std::string kName = "0x005e551000000001";  // kSession as notes name it

Bytes message(std::int64_t id, bool graph, std::size_t size = 100) {
  Bytes bytes(size, graph ? 0x99 : 0xaa);
  bytes[0] = static_cast<std::uint8_t>(id);
  return bytes;
}

// What a tracker publishes of keyframes [from, to): keyframe k, then (with keyframe k + 1, or at the
// session's end) its local graph; `last_graph` false: the last keyframe's graph is not out yet.
void publish(Delivery& delivery, std::int64_t from, std::int64_t to, Clock::time_point now,
             std::int64_t session = kSession, bool last_graph = true) {
  for (std::int64_t k = from; k < to; ++k) {
    delivery.published(session, k, false, message(k, false), now);
    if (k + 1 < to || last_graph) delivery.published(session, k, true, message(k, true), now);
  }
}

std::vector<Key> keys(const std::vector<Spool::Entry>& entries) {
  std::vector<Key> out;
  for (const auto& e : entries) out.emplace_back(e.session, e.id, e.graph);
  return out;
}

Delivery spooling(const fs::path& dir, std::uintmax_t bytes = kRoom) {
  std::string warning;
  Delivery delivery(dir.string(), bytes, kLinger, &warning);
  EXPECT_EQ(warning, "");
  return delivery;
}

TEST(Delivery, WhatIsPublishedIsKeptInTheSpool) {
  test::TempDir dir;
  auto delivery = spooling(dir.path());
  publish(delivery, 0, 2, t0);
  for (std::int64_t k = 0; k < 2; ++k)
    for (const bool graph : {false, true}) EXPECT_EQ(delivery.spooled(kSession, k, graph), message(k, graph));
  EXPECT_EQ(delivery.spooled(kSession, 2, false), std::nullopt);
  EXPECT_TRUE(delivery.left_over(kSession).empty()) << "this run's own session is not left over";
  EXPECT_EQ(delivery.spool_note(), "");
}

TEST(Delivery, AKeyframeIsWaitedForOnceItsLocalGraphIsPublished) {
  test::TempDir dir;
  auto delivery = spooling(dir.path());
  publish(delivery, 0, 3, t0, kSession, false);  // keyframe 2's graph not out yet
  delivery.acknowledged(kSession, 0, t0 + 1s);   // a back end heard: it holds nothing yet
  EXPECT_EQ(delivery.due(t0 + 5s), (Due{{kSession, 0}, {kSession, 1}}));
  EXPECT_NE(delivery.unacknowledged_note().find("keyframes 0-1 of session " + kName), std::string::npos)
      << delivery.unacknowledged_note();

  delivery.published(kSession, 2, true, message(2, true), t0 + 2s);
  EXPECT_NE(delivery.unacknowledged_note().find("keyframes 0-2 of session " + kName), std::string::npos)
      << delivery.unacknowledged_note();
  const auto ready = t0 + 2s;
  delivery.acknowledged(kSession, 0, ready + Acknowledgements::kFirstWait - 1s);  // heard again
  EXPECT_TRUE(delivery.due(ready + Acknowledgements::kFirstWait - 1s).empty())
      << "keyframe 2 waits from when its graph went out";
  EXPECT_EQ(delivery.due(ready + Acknowledgements::kFirstWait), (Due{{kSession, 2}}));
}

TEST(Delivery, AnAcknowledgementOfASessionWithNothingReadyIsIgnored) {
  test::TempDir dir;
  auto delivery = spooling(dir.path());
  publish(delivery, 0, 1, t0, kSession, false);  // keyframe 0 without its graph
  delivery.acknowledged(kSession, 1, t0 + 1s);
  EXPECT_EQ(delivery.spooled(kSession, 0, false), message(0, false)) << "not removed from the spool";
  EXPECT_TRUE(delivery.may_exit(t0 + 1s, t0 + 1s)) << "no back end heard of our sessions";
}

TEST(Delivery, AnAcknowledgementRemovesWhatTheBackEndHoldsFromTheSpool) {
  test::TempDir dir;
  auto delivery = spooling(dir.path());
  publish(delivery, 0, 4, t0);
  publish(delivery, 0, 1, t0, kOther);
  delivery.acknowledged(kSession, 3, t0 + 1s);
  for (std::int64_t k = 0; k < 3; ++k) EXPECT_EQ(delivery.spooled(kSession, k, false), std::nullopt) << k;
  EXPECT_EQ(delivery.spooled(kSession, 3, false), message(3, false));
  EXPECT_EQ(delivery.spooled(kSession, 3, true), message(3, true));
  EXPECT_EQ(delivery.spooled(kOther, 0, false), message(0, false)) << "another session's";
  EXPECT_EQ(delivery.due(t0 + 5s), (Due{{kSession, 3}})) << "kOther's back end was never heard";
}

// Issue 48: a word that says the back end holds keyframes below a million, when keyframes 0-2 are
// out, covers those three only: the spool keeps what is made after it, and that is waited for.
TEST(Delivery, AnAcknowledgementBeyondWhatWasPublishedCoversOnlyWhatWas) {
  test::TempDir dir;
  auto delivery = spooling(dir.path());
  publish(delivery, 0, 3, t0);
  EXPECT_EQ(delivery.acknowledged(kSession, 1'000'000, t0 + 1s), 3) << "taken below the newest published, 2";
  EXPECT_EQ(delivery.spooled(kSession, 2, true), std::nullopt) << "what it covers leaves the spool";
  publish(delivery, 3, 5, t0 + 2s);
  for (std::int64_t k = 3; k < 5; ++k)
    for (const bool graph : {false, true}) EXPECT_EQ(delivery.spooled(kSession, k, graph), message(k, graph)) << k;
  EXPECT_NE(delivery.unacknowledged_note().find("keyframes 3-4 of session " + kName), std::string::npos)
      << delivery.unacknowledged_note();
  EXPECT_FALSE(delivery.may_exit(t0 + 3s, t0 + 3s)) << "they are waited for";
  EXPECT_EQ(delivery.acknowledged(kOther, 1'000'000, t0 + 3s), std::nullopt) << "not a session of ours";
}

// The open keyframe (its local graph not out yet) cannot be held by any back end: whatever a word
// claims, it stays in the spool, and once its graph is out it is waited for.
TEST(Delivery, TheSpoolKeepsTheOpenKeyframeWhateverAnAcknowledgementClaims) {
  test::TempDir dir;
  auto delivery = spooling(dir.path());
  publish(delivery, 0, 4, t0, kSession, false);  // keyframe 3's graph not out yet
  EXPECT_EQ(delivery.acknowledged(kSession, 1'000'000, t0 + 1s), 3);
  EXPECT_EQ(delivery.spooled(kSession, 3, false), message(3, false));
  delivery.published(kSession, 3, true, message(3, true), t0 + 2s);
  EXPECT_EQ(delivery.spooled(kSession, 3, true), message(3, true));
  EXPECT_NE(delivery.unacknowledged_note().find("keyframes 3 of session " + kName), std::string::npos)
      << delivery.unacknowledged_note();
}

// A session handed over is published as far as the spool held it: its newest keyframe, even one
// without its graph (a killed session's last), bounds what may be acknowledged of it.
TEST(Delivery, AHandedOverSessionIsAcknowledgedNoFurtherThanWhatWasHandedOver) {
  test::TempDir dir;
  {
    auto killed = spooling(dir.path());
    publish(killed, 0, 3, t0, kOther, false);  // keyframes 0-2, the graph of 2 never out
  }
  auto delivery = spooling(dir.path());
  EXPECT_EQ(delivery.newest_published(kOther), std::nullopt) << "not handed over yet";
  delivery.handed_over(delivery.left_over(kSession), t0);
  EXPECT_EQ(delivery.newest_published(kOther), 2);
  EXPECT_EQ(delivery.acknowledged(kOther, 1'000'000, t0 + 1s), 3);
  EXPECT_EQ(delivery.acknowledged(kOther, 2, t0 + 2s), 2) << "a word within it is taken whole";
}

TEST(Delivery, SendsAgainAtMostTwoKeyframesOfEachSessionARound) {
  test::TempDir dir;
  auto delivery = spooling(dir.path());
  publish(delivery, 0, 3, t0);
  publish(delivery, 0, 3, t0, kOther);
  delivery.acknowledged(kSession, 0, t0 + 5s);
  delivery.acknowledged(kOther, 1, t0 + 5s);
  EXPECT_EQ(delivery.due(t0 + 5s), (Due{{kSession, 0}, {kSession, 1}, {kOther, 1}, {kOther, 2}}));
  EXPECT_EQ(delivery.due(t0 + 5s), (Due{{kSession, 2}}));
  EXPECT_TRUE(delivery.due(t0 + 5s).empty());
}

TEST(Delivery, MayExitAtOnceWhenNoBackEndEverAcknowledgedAnything) {
  test::TempDir dir;
  auto delivery = spooling(dir.path());
  publish(delivery, 0, 5, t0);
  EXPECT_TRUE(delivery.may_exit(t0, t0));
  EXPECT_NE(delivery.unacknowledged_note().find("keyframes 0-4 of session " + kName), std::string::npos)
      << "all of it unacknowledged: " << delivery.unacknowledged_note();
}

TEST(Delivery, WaitsWhileSomethingIsUnacknowledgedWithinTheLinger) {
  test::TempDir dir;
  auto delivery = spooling(dir.path());
  publish(delivery, 0, 5, t0);
  delivery.acknowledged(kSession, 3, t0 + 1s);
  const auto done = t0 + 2s;
  EXPECT_FALSE(delivery.may_exit(done, done));
  EXPECT_FALSE(delivery.may_exit(done, done + 9s));
  EXPECT_TRUE(delivery.may_exit(done, done + 10s)) << "the linger (10 s) passed";
  EXPECT_TRUE(delivery.may_exit(done, done + 1h));
}

TEST(Delivery, MayExitOnceEverythingIsAcknowledged) {
  test::TempDir dir;
  auto delivery = spooling(dir.path());
  publish(delivery, 0, 5, t0);
  publish(delivery, 0, 2, t0, kOther);
  delivery.acknowledged(kSession, 5, t0 + 1s);
  EXPECT_FALSE(delivery.may_exit(t0 + 2s, t0 + 2s)) << "kOther's keyframes are not acknowledged";
  delivery.acknowledged(kOther, 2, t0 + 3s);
  EXPECT_TRUE(delivery.may_exit(t0 + 2s, t0 + 3s));
  EXPECT_EQ(delivery.unacknowledged_note(), "");
}

TEST(Delivery, TheNoteNamesWhatIsUnacknowledgedAsRangesOfEachSession) {
  test::TempDir dir;
  auto delivery = spooling(dir.path());
  publish(delivery, 0, 10, t0);
  publish(delivery, 0, 1, t0, kOther);
  delivery.acknowledged(kSession, 3, t0 + 1s);
  delivery.acknowledged(kOther, 0, t0 + 1s);
  EXPECT_EQ(delivery.unacknowledged_note(),
            "keyframes 3-9 of session 0x005e551000000001; keyframes 0 of session 0x005e551000000002 not "
            "acknowledged by the back end (kept in the spool for the next start)");
}

TEST(Delivery, WithoutASpoolTheNoteSaysWhatIsLost) {
  std::string warning;
  Delivery delivery("", kRoom, kLinger, &warning);
  EXPECT_EQ(warning, "") << "no spool asked for: nothing to warn of";
  publish(delivery, 0, 6, t0);
  EXPECT_EQ(delivery.spooled(kSession, 0, false), std::nullopt);
  EXPECT_TRUE(delivery.left_over(kOther).empty());
  delivery.acknowledged(kSession, 3, t0 + 1s);
  EXPECT_EQ(delivery.unacknowledged_note(),
            "keyframes 3-5 of session " + kName +
                " not acknowledged by the back end (no trackerd.spool: lost if the back end lacks them)");
  EXPECT_EQ(delivery.spool_note(), "");
}

TEST(Delivery, ASpoolThatCannotBeOpenedIsNoneAndSaysSo) {
  test::TempDir dir;
  const auto in_the_way = dir.write("a-file", "in the way");
  std::string warning;
  Delivery delivery((in_the_way / "spool").string(), kRoom, kLinger, &warning);
  EXPECT_NE(warning.find((in_the_way / "spool").string()), std::string::npos) << warning;
  EXPECT_NE(warning.find("running without a spool"), std::string::npos) << warning;
  publish(delivery, 0, 1, t0);
  EXPECT_EQ(delivery.spooled(kSession, 0, false), std::nullopt);
}

// A killed session's newest keyframe never had its local graph published: handed over, it is not
// waited for (the back end acknowledges a keyframe with its graph), and it leaves the spool once
// everything before it is acknowledged.
TEST(Delivery, AKeyframeHandedOverWithoutItsGraphIsNotWaitedForAndLeavesOnceAllBeforeItAreHeld) {
  test::TempDir dir;
  {
    auto killed = spooling(dir.path());
    publish(killed, 0, 3, t0, kOther, false);  // keyframes 0-2, the graph of 2 never out
  }
  auto delivery = spooling(dir.path());
  delivery.handed_over(delivery.left_over(kSession), t0);
  delivery.acknowledged(kOther, 2, t0 + 1s);
  EXPECT_TRUE(delivery.may_exit(t0 + 1s, t0 + 1s)) << "keyframe 2 is not waited for";
  EXPECT_FALSE(delivery.spooled(kOther, 2, false)) << "all before it held: it leaves the spool";
  EXPECT_TRUE(delivery.left_over(kSession).empty());
}

TEST(Delivery, WhatAnEarlierRunLeftIsListedForHandingOverAndWaitedFor) {
  test::TempDir dir;
  {
    auto killed = spooling(dir.path());  // an earlier run, killed before the back end held keyframe 1
    publish(killed, 0, 2, t0, kOther);
    killed.acknowledged(kOther, 1, t0 + 1s);
  }
  // Oldest first by the files' times (the kernel's are coarse: made a second apart here).
  const auto start = fs::file_time_type::clock::now() - 1h;
  fs::last_write_time(dir.path() / "005e551000000002-1-k.lcm", start);
  fs::last_write_time(dir.path() / "005e551000000002-1-g.lcm", start + 1s);

  auto delivery = spooling(dir.path());
  const auto left = delivery.left_over(kSession);
  EXPECT_EQ(keys(left), (std::vector<Key>{{kOther, 1, false}, {kOther, 1, true}}));
  EXPECT_TRUE(delivery.left_over(kOther).empty()) << "a session of its own is not left over";
  EXPECT_EQ(delivery.spooled(kOther, 1, false), message(1, false));
  EXPECT_EQ(delivery.spooled(kOther, 1, true), message(1, true));

  delivery.handed_over(left, t0 + 10s);
  EXPECT_NE(delivery.unacknowledged_note().find("keyframes 1 of session 0x005e551000000002"), std::string::npos)
      << delivery.unacknowledged_note();
  delivery.acknowledged(kOther, 1, t0 + 11s);
  EXPECT_FALSE(delivery.may_exit(t0 + 11s, t0 + 11s));
  EXPECT_EQ(delivery.due(t0 + 15s), (Due{{kOther, 1}}));
  delivery.acknowledged(kOther, 2, t0 + 16s);
  EXPECT_TRUE(delivery.may_exit(t0 + 11s, t0 + 16s));
  EXPECT_EQ(delivery.spooled(kOther, 1, false), std::nullopt) << "handed over and held: gone from the spool";
  EXPECT_TRUE(spooling(dir.path()).left_over(kSession).empty()) << "nothing left for the next run";
}

TEST(Delivery, TheSpoolNoteReportsKeyframesDroppedForRoomOnce) {
  test::TempDir dir;
  auto delivery = spooling(dir.path(), 350);
  publish(delivery, 0, 3, t0);  // 600 bytes, 100 each: the oldest three (keyframes 0-1, graph 0) go
  EXPECT_EQ(delivery.spool_note(), "spool full (trackerd.spool_bytes): dropped keyframes 0-1 of session " + kName);
  EXPECT_EQ(delivery.spool_note(), "") << "reported once";
  EXPECT_EQ(delivery.spooled(kSession, 2, true), message(2, true));
}

TEST(Delivery, TheSpoolNoteReportsMessagesThatWereNotSpooled) {
  test::TempDir dir;
  auto delivery = spooling(dir.path(), 150);
  delivery.published(kSession, 0, false, message(0, false, 200), t0);
  delivery.published(kSession, 0, true, message(0, true, 200), t0);
  EXPECT_EQ(delivery.spool_note(), "2 messages not spooled: larger than trackerd.spool_bytes");
  EXPECT_EQ(delivery.spool_note(), "");
  EXPECT_EQ(delivery.spooled(kSession, 0, false), std::nullopt);
  EXPECT_NE(delivery.unacknowledged_note().find("keyframes 0 of session " + kName), std::string::npos)
      << "waited for all the same: " << delivery.unacknowledged_note();
}

}  // namespace
}  // namespace cvo::daemon::trackerd
