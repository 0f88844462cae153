// Signed messages verify on the channel they were signed for and nowhere else; any changed byte, an
// unsigned message or another deployment's key is refused as kAuth; a counter seen already, below
// the window or older than max_age is refused as kReplay; rotation keeps two keys accepted.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

#include "cvo_lcm/auth_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "libcvo/auth/authenticator.hpp"
#include "libcvo/auth/sender.hpp"

namespace cvo::auth {
namespace {

constexpr std::int64_t kMaxAge = 30'000'000;  // 30 s
constexpr std::int64_t kSender = 0x5e4d;

std::shared_ptr<const KeyRing> ring_of(std::vector<Key> keys) {
  return std::make_shared<const KeyRing>(std::move(keys));
}

std::shared_ptr<const KeyRing> one_key() {
  std::vector<Key> keys;
  keys.push_back(Key::generate());
  return ring_of(std::move(keys));
}

std::vector<std::uint8_t> pose_bytes(std::int64_t frame_index = 7) {
  cvo_lcm::pose_t m{};
  m.version = cvo_lcm::pose_t::SCHEMA_VERSION;
  m.frame_index = frame_index;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

std::int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

TEST(Trailer, IsTheLastFieldOfEveryMessageAndItsLast56Bytes) {
  EXPECT_EQ(cvo_lcm::auth_t{}.getEncodedSize(), static_cast<int>(8 + kTrailerBytes));  // fingerprint + fields
  cvo_lcm::pose_t m{};
  m.auth.sender = 11;
  m.auth.counter = 22;
  m.auth.key_id = 33;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  const Trailer t = read_trailer(bytes.data(), bytes.size());
  EXPECT_EQ(t.sender, 11);
  EXPECT_EQ(t.counter, 22);
  EXPECT_EQ(t.key_id, 33);
}

TEST(SignedMessages, VerifyOnTheirChannelWithTheirSender) {
  const auto keys = one_key();
  Signer signer(keys, kSender);
  auto bytes = pose_bytes();
  signer.sign("CVO_POSE", bytes);
  Verifier verifier(keys, kMaxAge);
  const auto v = verifier.verify("CVO_POSE", bytes.data(), bytes.size());
  EXPECT_EQ(v.verdict, Verdict::kOk) << v.why;
  EXPECT_EQ(v.sender, kSender);
  EXPECT_TRUE(v.authenticated);
  EXPECT_EQ(read_trailer(bytes.data(), bytes.size()).key_id, keys->signing().id());
}

TEST(SignedMessages, AnyChangedByteIsRefusedAsAuth) {
  const auto keys = one_key();
  Signer signer(keys, kSender);
  auto signed_bytes = pose_bytes();
  signer.sign("CVO_POSE", signed_bytes);
  // The fingerprint, the body, each trailer field and the authenticator itself.
  for (const std::size_t at :
       {std::size_t{0}, std::size_t{20}, signed_bytes.size() - kTrailerBytes, signed_bytes.size() - kTrailerBytes + 8,
        signed_bytes.size() - kTrailerBytes + 16, signed_bytes.size() - 1}) {
    auto bytes = signed_bytes;
    bytes[at] ^= 0x01;
    Verifier verifier(keys, kMaxAge);
    EXPECT_EQ(verifier.verify("CVO_POSE", bytes.data(), bytes.size()).verdict, Verdict::kAuth) << "byte " << at;
  }
}

TEST(SignedMessages, OnAnotherChannelAreRefusedAsAuth) {
  const auto keys = one_key();
  Signer signer(keys, kSender);
  auto bytes = pose_bytes();
  signer.sign("CVO_POSE", bytes);
  Verifier verifier(keys, kMaxAge);
  EXPECT_EQ(verifier.verify("CVO_POSES", bytes.data(), bytes.size()).verdict, Verdict::kAuth);
}

TEST(SignedMessages, OfAnotherDeploymentAreRefusedAsAuth) {
  Signer theirs(one_key(), kSender);
  auto bytes = pose_bytes();
  theirs.sign("CVO_POSE", bytes);
  Verifier ours(one_key(), kMaxAge);
  const auto v = ours.verify("CVO_POSE", bytes.data(), bytes.size());
  EXPECT_EQ(v.verdict, Verdict::kAuth);
  EXPECT_NE(std::string(v.why).find("does not hold"), std::string::npos) << v.why;
}

TEST(SignedMessages, UnsignedOrTooShortAreRefusedWhenAKeyIsHeld) {
  Verifier verifier(one_key(), kMaxAge);
  const auto bytes = pose_bytes();  // trailer zero: what an open-bus sender publishes
  EXPECT_EQ(verifier.verify("CVO_POSE", bytes.data(), bytes.size()).verdict, Verdict::kAuth);
  EXPECT_EQ(verifier.verify("CVO_POSE", bytes.data(), 10).verdict, Verdict::kAuth);
  EXPECT_EQ(verifier.verify("CVO_POSE", nullptr, 0).verdict, Verdict::kAuth);
}

TEST(OpenBus, SignsNothingAndAcceptsEverything) {
  Signer signer(nullptr, kSender);
  auto bytes = pose_bytes();
  const auto before = bytes;
  signer.sign("CVO_POSE", bytes);
  EXPECT_EQ(bytes, before) << "an open bus leaves the trailer zero: the bytes as before";
  Verifier verifier(nullptr, kMaxAge);
  for (int i = 0; i < 2; ++i) {
    const auto v = verifier.verify("CVO_POSE", bytes.data(), bytes.size());
    EXPECT_EQ(v.verdict, Verdict::kOk);
    EXPECT_FALSE(v.authenticated);
    EXPECT_EQ(v.sender, 0) << "nothing proves a sender on an open bus: all are one";
  }
}

TEST(Replay, TheSameMessageTwiceIsRefusedTheSecondTime) {
  const auto keys = one_key();
  Signer signer(keys, kSender);
  auto bytes = pose_bytes();
  signer.sign("CVO_POSE", bytes);
  Verifier verifier(keys, kMaxAge);
  EXPECT_EQ(verifier.verify("CVO_POSE", bytes.data(), bytes.size()).verdict, Verdict::kOk);
  const auto again = verifier.verify("CVO_POSE", bytes.data(), bytes.size());
  EXPECT_EQ(again.verdict, Verdict::kReplay);
  EXPECT_EQ(again.sender, kSender);
  // Signed afresh (a keyframe re-sent on request), the same content is a new message.
  signer.sign("CVO_POSE", bytes);
  EXPECT_EQ(verifier.verify("CVO_POSE", bytes.data(), bytes.size()).verdict, Verdict::kOk);
}

TEST(Replay, AnOldRecordingIsRefusedByAReceiverThatNeverSawItsSender) {
  const auto keys = one_key();
  Signer signer(keys, kSender);
  auto bytes = pose_bytes();
  signer.sign("CVO_POSE", bytes);
  Verifier fresh_receiver(keys, kMaxAge);
  const auto later = now_us() + kMaxAge + 1'000'000;  // played back 31 s after it was sent
  const auto v = fresh_receiver.verify("CVO_POSE", bytes.data(), bytes.size(), later);
  EXPECT_EQ(v.verdict, Verdict::kReplay);
  EXPECT_NE(std::string(v.why).find("max_age"), std::string::npos) << v.why;
  // A log read on purpose (file://) is checked for authenticity only.
  Verifier log_reader(keys, kMaxAge, false);
  EXPECT_EQ(log_reader.verify("CVO_POSE", bytes.data(), bytes.size(), later).verdict, Verdict::kOk);
}

TEST(Replay, CountersIncreaseAcrossARestartOfTheSender) {
  const auto keys = one_key();
  std::vector<std::uint8_t> first = pose_bytes(), second = pose_bytes();
  Signer(keys, kSender).sign("CVO_POSE", first);
  std::this_thread::sleep_for(std::chrono::milliseconds(1));  // a restart takes longer than a microsecond
  Signer(keys, kSender).sign("CVO_POSE", second);             // the sender restarted: same id, new Signer
  EXPECT_LT(read_trailer(first.data(), first.size()).counter, read_trailer(second.data(), second.size()).counter);
  Verifier verifier(keys, kMaxAge);
  EXPECT_EQ(verifier.verify("CVO_POSE", first.data(), first.size()).verdict, Verdict::kOk);
  EXPECT_EQ(verifier.verify("CVO_POSE", second.data(), second.size()).verdict, Verdict::kOk);
}

TEST(ReplayWindow, TakesMessagesThatArriveOutOfOrderWithinTheWindow) {
  ReplayWindow window(kMaxAge);
  const std::int64_t now = now_us();
  EXPECT_TRUE(window.accept(kSender, now - 100, now).accepted);
  EXPECT_TRUE(window.accept(kSender, now - 50'000, now).accepted == false) << "below the first seen";
  EXPECT_TRUE(window.accept(kSender, now + 5'000, now).accepted);
  EXPECT_TRUE(window.accept(kSender, now + 1'000, now).accepted) << "sent before the last, arrived after it";
  EXPECT_FALSE(window.accept(kSender, now + 1'000, now).accepted) << "seen";
}

TEST(ReplayWindow, RefusesWhatFellOutOfTheWindowOf64Messages) {
  ReplayWindow window(kMaxAge);
  const std::int64_t now = now_us();
  for (std::int64_t i = 0; i < 64; i += 2) ASSERT_TRUE(window.accept(kSender, now + i, now).accepted);
  EXPECT_TRUE(window.accept(kSender, now + 1, now).accepted) << "a gap in the window, filled once";
  for (std::int64_t i = 64; i < 200; ++i) ASSERT_TRUE(window.accept(kSender, now + i, now).accepted);
  EXPECT_FALSE(window.accept(kSender, now + 3, now).accepted) << "never seen, but below the window";
  EXPECT_FALSE(window.accept(kSender, now + 199, now).accepted);
  EXPECT_TRUE(window.accept(kSender, now + 200, now).accepted);
}

TEST(ReplayWindow, KeepsABoundedTableOfSendersForgettingTheSilentFirst) {
  ReplayWindow window(kMaxAge, 4);
  const std::int64_t now = now_us();
  for (std::int64_t s = 1; s <= 10; ++s) ASSERT_TRUE(window.accept(s, now + s, now + s).accepted);
  EXPECT_EQ(window.senders(), 4u);
  // Senders silent for longer than max_age go first: their old counters are refused by age anyway.
  ReplayWindow aged(kMaxAge, 2);
  ASSERT_TRUE(aged.accept(1, now, now).accepted);
  ASSERT_TRUE(aged.accept(2, now + 2 * kMaxAge, now + 2 * kMaxAge).accepted);
  ASSERT_TRUE(aged.accept(3, now + 2 * kMaxAge, now + 2 * kMaxAge).accepted);
  EXPECT_FALSE(aged.accept(2, now + 2 * kMaxAge, now + 2 * kMaxAge).accepted) << "sender 2 kept its window";
}

TEST(Rotation, AFileOfTwoKeysSignsWithTheFirstAndAcceptsBoth) {
  auto a = Key::generate();
  auto b = Key::generate();
  const auto a_id = a.id();
  const auto b_id = b.id();
  std::vector<Key> ab;
  ab.push_back(std::move(a));
  ab.push_back(std::move(b));
  const auto both = ring_of(std::move(ab));
  ASSERT_EQ(both->signing().id(), a_id);
  ASSERT_NE(both->find(b_id), nullptr);
  Signer stage_one(both, kSender);  // {A, B}: A signs
  auto bytes = pose_bytes();
  stage_one.sign("CVO_POSE", bytes);
  EXPECT_EQ(read_trailer(bytes.data(), bytes.size()).key_id, a_id);
  Verifier verifier(both, kMaxAge);
  EXPECT_EQ(verifier.verify("CVO_POSE", bytes.data(), bytes.size()).verdict, Verdict::kOk);
}

TEST(SenderIds, AreStablePerDaemonAndDistinctBetweenDaemons) {
  const auto id = sender_id("machine-1", "cvo-trackerd", "cvo-trackerd.service");
  EXPECT_EQ(id, sender_id("machine-1", "cvo-trackerd", "cvo-trackerd.service")) << "a restart keeps it";
  EXPECT_NE(id, sender_id("machine-1", "cvo-trackerd", "cvo-trackerd@rear.service")) << "a second tracker";
  EXPECT_NE(id, sender_id("machine-2", "cvo-trackerd", "cvo-trackerd.service")) << "another robot";
  EXPECT_NE(id, sender_id("machine-1", "cvo-backendd", "cvo-trackerd.service"));
  EXPECT_NE(sender_id("ab", "c", ""), sender_id("a", "bc", ""));
  // Started by hand (no unit of its own): a sender of its own every start.
  EXPECT_NE(this_process_sender_id("cvo-trackerd"), this_process_sender_id("cvo-trackerd"));
}

TEST(SenderIds, NameTheServiceUnitFromTheCgroup) {
  EXPECT_EQ(service_unit("0::/system.slice/cvo-trackerd.service\n"), "cvo-trackerd.service");
  EXPECT_EQ(service_unit("1:name=systemd:/system.slice/cvo-trackerd@rear.service/x\n0::/\n"),
            "cvo-trackerd@rear.service");
  EXPECT_EQ(service_unit("0::/user.slice/user-1000.slice/session-3.scope\n"), "");
  EXPECT_EQ(service_unit("0::/\n"), "");
}

}  // namespace
}  // namespace cvo::auth
