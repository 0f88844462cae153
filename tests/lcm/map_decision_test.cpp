// What a tracker makes of a received CVO_MAP (lcm::decide_map_correction) or CVO_MAP_CORRECTION
// (lcm::decide_session_correction), without LCM: only a newer word with a finite, plausible entry
// for its own session moves its map poses; a stale, a foreign, an implausible or a non-finite one is
// refused by its own kind and changes nothing; both channels are one decision; and only a word the
// tracker trusts acknowledges what the back end holds (its spool deletes what is acknowledged).
#include <cmath>
#include <limits>
#include <utility>

#include <gtest/gtest.h>

#include "cvo_lcm/map_t.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/map_conversion.hpp"
#include "libcvo/lcm/map_correction_conversion.hpp"
#include "libcvo/lcm/map_decision.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "tests/support/map_session.hpp"

namespace cvo::lcm {
namespace {

using core::BadKind;

constexpr std::int64_t kSession = 0x1234'5678'9abc'def0;
constexpr std::int64_t kOther = 77;
const CorrectionLimits kLimits{1.0, 30.0};

// The bytes of a map of `revision` (of a back end started at `epoch`) placing each of `sessions`
// with its correction.
std::vector<std::uint8_t> map_bytes(std::int64_t revision, const std::vector<slam::MapSession>& sessions,
                                    std::int64_t epoch = 0) {
  slam::Map map;
  map.revision = static_cast<std::uint64_t>(revision);
  map.sessions = sessions;
  for (const auto& s : sessions) map.keyframes.push_back({s.session, 0, 1.5, s.correction});
  return encode(to_message(map, 1, epoch));
}

slam::MapSession placed(std::int64_t session, const core::SE3& correction) {
  return test::map_session(session, true, kOther, 1, 0, correction);
}

// The receiver's clock: ten seconds after the epochs of the maps below (µs since 1970, as epochs).
constexpr std::int64_t kNow = 10'000'000;

CorrectionDecision decide(const std::vector<std::uint8_t>& bytes, const AppliedCorrection& last,
                          const MapContext& context = {kNow, 0, {}}) {
  return decide_map_correction(bytes.data(), static_cast<int>(bytes.size()), kSession, last, kLimits, context);
}

const core::SE3 kOneMetre = core::SE3::from_translation({1, 0, 0});

TEST(MapDecision, ANewerMapPlacingTheSessionIsApplied) {
  const auto d = decide(map_bytes(3, {placed(kOther, {}), placed(kSession, kOneMetre)}), AppliedCorrection{});
  ASSERT_TRUE(d.apply) << d.why;
  EXPECT_EQ(d.correction.revision, 3);
  EXPECT_EQ(d.correction.session, kSession);
  EXPECT_TRUE(d.correction.placed);
  EXPECT_LT((d.correction.T_map_odom.translation() - kOneMetre.translation()).norm(), 1e-12);

  // Any first placement is taken, however far (the map frame is another session's); and an entry
  // of a newer back end (epoch) that is not placed returns the session to its odometry frame.
  const auto far =
      decide(map_bytes(4, {placed(kSession, core::SE3::from_translation({40, 0, 0}))}), AppliedCorrection{});
  EXPECT_TRUE(far.apply) << far.why;
  const auto unplaced =
      decide(map_bytes(1, {test::map_session(kSession, false, kSession, 1, -1, kOneMetre)}, 5), d.correction);
  ASSERT_TRUE(unplaced.apply) << unplaced.why;
  EXPECT_FALSE(unplaced.correction.placed);
  EXPECT_EQ(unplaced.correction.T_map_odom.translation().norm(), 0) << "identity when not placed";
}

TEST(MapDecision, TheSessionsLastMatchAndKeyframeCovarianceComeWithItsCorrection) {
  slam::MapSession s = test::map_session(kSession, true, kOther, 1, 0, kOneMetre);
  s.last_match_time = 1305031102.5;
  s.keyframe_covariance = core::Matrix6d::Identity() * 4e-4;
  s.covariance_keyframe = 9;
  const auto d = decide(map_bytes(3, {s}), AppliedCorrection{});
  ASSERT_TRUE(d.apply) << d.why;
  EXPECT_NEAR(d.correction.last_match_time, 1305031102.5, 1e-6);
  ASSERT_TRUE(d.correction.keyframe_covariance);
  EXPECT_EQ((*d.correction.keyframe_covariance)(4, 4), 4e-4);
  EXPECT_EQ(d.correction.covariance_keyframe, 9);
  // A covariance that is not one (negative variance) makes the map refused whole.
  s.keyframe_covariance = -core::Matrix6d::Identity();
  EXPECT_FALSE(decide(map_bytes(4, {s}), AppliedCorrection{}).apply);
}

TEST(MapDecision, StaleForeignImplausibleAndNonFiniteMapsAreRefusedByKind) {
  const AppliedCorrection last{0, 7, kSession, true, kOneMetre, -1, std::nullopt, -1};
  const auto refused = [&](const std::vector<std::uint8_t>& bytes, BadKind kind, const char* says) {
    const auto d = decide(bytes, last);
    EXPECT_FALSE(d.apply);
    EXPECT_EQ(d.refusal, kind) << d.why;
    EXPECT_NE(d.why.find(says), std::string::npos) << d.why;
  };
  const auto nearby = core::SE3::from_translation({1.2, 0, 0});
  refused(map_bytes(6, {placed(kSession, nearby)}), BadKind::kStale,
          "revision 6 of epoch 0, not newer than the applied revision 7");
  refused(map_bytes(7, {placed(kSession, nearby)}), BadKind::kStale, "revision 7 of epoch 0, not newer");  // a replay
  refused(map_bytes(8, {placed(kOther, nearby)}), BadKind::kForeign, "no entry for this session");
  refused(map_bytes(8, {placed(kSession, core::SE3::from_translation({3, 0, 0}))}), BadKind::kImplausible,
          "jumps 2.00 m and 0.00 deg");
  refused(map_bytes(8, {placed(kSession, kOneMetre * core::SE3::from_rotation_vector({0, 0, 0.7}))}),
          BadKind::kImplausible, "and 40.11 deg");
  auto nan = to_message(slam::Map{8, {placed(kSession, nearby)}, {}, {}}, 1);
  nan.sessions[0].correction.position[1] = std::numeric_limits<double>::quiet_NaN();
  refused(encode(nan), BadKind::kNotFinite, "not finite");
  auto bad_version = to_message(slam::Map{8, {placed(kSession, nearby)}, {}, {}}, 1);
  bad_version.version = 1;
  refused(encode(bad_version), BadKind::kVersion, "schema version 1");
  const std::vector<std::uint8_t> short_bytes = {1, 2, 3};
  refused(short_bytes, BadKind::kTooShort, "shorter than");

  // Within the bound it is applied; the bound is the caller's.
  EXPECT_TRUE(decide(map_bytes(8, {placed(kSession, nearby)}), last).apply);
  const auto far = map_bytes(8, {placed(kSession, core::SE3::from_translation({3, 0, 0}))});
  EXPECT_TRUE(
      decide_map_correction(far.data(), static_cast<int>(far.size()), kSession, last, {5.0, 30.0}, {kNow, 0, {}})
          .apply);
}

// A back end that restarts numbers its revisions afresh in a newer epoch: its first map is taken
// (the tracker must not wait for the revision to pass the old one), and a map of the old epoch,
// replayed, is stale.
TEST(MapDecision, ARestartedBackEndsMapsAreNewerThanItsPredecessors) {
  const AppliedCorrection last{1000, 250, kSession, true, kOneMetre, -1, std::nullopt, -1};
  const auto restarted = decide(map_bytes(1, {placed(kSession, kOneMetre)}, 2000), last);
  ASSERT_TRUE(restarted.apply) << restarted.why;
  EXPECT_EQ(restarted.correction.epoch, 2000);
  EXPECT_EQ(restarted.correction.revision, 1);
  const auto replayed = decide(map_bytes(900, {placed(kSession, kOneMetre)}, 500), last);
  EXPECT_FALSE(replayed.apply);
  EXPECT_EQ(replayed.refusal, BadKind::kStale);
}

TEST(MapDecision, TheJumpBoundHoldsOnlyWithinTheSessionItPlaced) {
  // The last correction was for a session the tracker has left (a camera change): the new
  // session's first placement is not a jump from it.
  const AppliedCorrection other_session{0, 7, kOther, true, kOneMetre, -1, std::nullopt, -1};
  const auto d = decide(map_bytes(8, {placed(kSession, core::SE3::from_translation({9, 0, 0}))}), other_session);
  EXPECT_TRUE(d.apply) << d.why;
  // Nor is a placement after the session was unplaced.
  const AppliedCorrection unplaced{0, 7, kSession, false, {}, -1, std::nullopt, -1};
  EXPECT_TRUE(decide(map_bytes(8, {placed(kSession, core::SE3::from_translation({9, 0, 0}))}), unplaced).apply);
}

// A map from the future would win over every real back end (a newer epoch always wins): an epoch
// beyond the clock slack is refused, and the genuine back end's next map is applied as if it had
// never come.
TEST(MapDecision, AnEpochFromTheFarFutureIsRefusedAndLocksNoBackEndOut) {
  const AppliedCorrection last{0, 7, kSession, true, kOneMetre, -1, std::nullopt, -1};
  const std::int64_t in_a_year = kNow + 365LL * 86400 * 1'000'000;
  const auto future = decide(map_bytes(8, {placed(kSession, kOneMetre)}, in_a_year), last);
  EXPECT_FALSE(future.apply);
  EXPECT_EQ(future.refusal, BadKind::kImplausible);
  EXPECT_NE(future.why.find("in the future of this clock"), std::string::npos) << future.why;
  EXPECT_TRUE(decide(map_bytes(8, {placed(kSession, kOneMetre)}), last).apply);
  // Within the slack (clocks of one deployment differ a little) a newer epoch is taken.
  EXPECT_TRUE(decide(map_bytes(1, {placed(kSession, kOneMetre)}, kNow + 5'000'000), last).apply);
}

// One map with a huge revision would make every real map stale: a revision may lead the applied
// one by at most revisions_per_s for each second since (and one second's worth at least).
TEST(MapDecision, ARevisionLeapBeyondTheBackEndsRateIsRefused) {
  AppliedCorrection last{0, 7, kSession, true, kOneMetre, -1, std::nullopt, -1};
  last.applied_utime = kNow - 2'000'000;  // two seconds ago: 200 revisions at 100 a second
  const auto leap = decide(map_bytes(7 + 1'000'000, {placed(kSession, kOneMetre)}), last);
  EXPECT_FALSE(leap.apply);
  EXPECT_EQ(leap.refusal, BadKind::kImplausible);
  EXPECT_NE(leap.why.find("leaps 1000000 revisions"), std::string::npos) << leap.why;
  EXPECT_FALSE(decide(map_bytes(7 + 201, {placed(kSession, kOneMetre)}), last).apply);
  EXPECT_TRUE(decide(map_bytes(7 + 200, {placed(kSession, kOneMetre)}), last).apply);
  // After a long silence (a link down for ten minutes) the back end's real progress is taken.
  last.applied_utime = kNow - 600'000'000;
  EXPECT_TRUE(decide(map_bytes(7 + 9000, {placed(kSession, kOneMetre)}), last).apply);
}

TEST(MapDecision, WithinAnEpochOnlyTheSenderOfTheAppliedMapMovesTheSession) {
  AppliedCorrection last{0, 7, kSession, true, kOneMetre, -1, std::nullopt, -1};
  last.sender = 5;
  const auto other = decide(map_bytes(8, {placed(kSession, kOneMetre)}), last, {kNow, 6, {}});
  EXPECT_FALSE(other.apply);
  EXPECT_EQ(other.refusal, BadKind::kConflict);
  EXPECT_NE(other.why.find("another sender"), std::string::npos) << other.why;
  const auto same = decide(map_bytes(8, {placed(kSession, kOneMetre)}), last, {kNow, 5, {}});
  ASSERT_TRUE(same.apply) << same.why;
  EXPECT_EQ(same.correction.sender, 5);
  EXPECT_EQ(same.correction.applied_utime, kNow);
  // A restarted back end (a newer epoch) is taken from whoever sends it.
  EXPECT_TRUE(decide(map_bytes(1, {placed(kSession, kOneMetre)}, 1000), last, {kNow, 6, {}}).apply);
}

// The attack of issue 26: "unplaced", then "placed 100 m away" sidestepped the jump bound.
TEST(MapDecision, APlacedSessionIsNotUnplacedWithinItsEpoch) {
  const AppliedCorrection last{0, 7, kSession, true, kOneMetre, -1, std::nullopt, -1};
  const auto unplaced = decide(map_bytes(8, {test::map_session(kSession, false, kSession, 1, -1, {})}), last);
  EXPECT_FALSE(unplaced.apply);
  EXPECT_EQ(unplaced.refusal, BadKind::kConflict);
  EXPECT_NE(unplaced.why.find("placed in this epoch"), std::string::npos) << unplaced.why;
  const auto far = decide(map_bytes(9, {placed(kSession, core::SE3::from_translation({100, 0, 0}))}), last);
  EXPECT_FALSE(far.apply);
  EXPECT_EQ(far.refusal, BadKind::kImplausible);
}

// A first placement C of the session must put its keyframe a where the map's loop from a to a
// placed keyframe b says: C · O_a = M_b · (T_a^b)⁻¹, up to the jump bound.
TEST(MapDecision, AFirstPlacementAgreesWithTheSessionsOwnLoops) {
  const core::SE3 O_a = core::SE3::from_translation({0.3, 0, 0});     // a's odometry pose
  const core::SE3 M_b = core::SE3::from_translation({5, 1, 0});       // b, in the map
  const core::SE3 T_ab = core::SE3::from_translation({0.2, 0, 0.1});  // the loop a -> b
  const core::SE3 C = M_b * T_ab.inverse() * O_a.inverse();           // what the loop implies
  const auto with_loop = [&](const core::SE3& correction) {
    slam::Map map;
    map.revision = 3;
    map.sessions = {placed(kOther, {}), placed(kSession, correction)};
    map.keyframes = {{kOther, 4, 1.0, M_b}, {kSession, 2, 1.5, correction * O_a}};
    auto m = to_message(map, 1, 0);
    cvo_lcm::map_loop_t loop{};
    loop.from_session = kSession;
    loop.to_session = kOther;
    loop.edge.from = 2;
    loop.edge.to = 4;
    loop.edge.measurement = to_message(T_ab);
    for (int i = 0; i < 6; ++i) loop.edge.information[i * 7] = 1;
    m.loops.push_back(loop);
    m.num_loops = 1;
    return encode(m);
  };
  const OwnKeyframe own[] = {{1, {}}, {2, O_a}};
  const auto agrees = decide(with_loop(C), AppliedCorrection{}, {kNow, 0, own});
  EXPECT_TRUE(agrees.apply) << agrees.why;
  const auto off = decide(with_loop(core::SE3::from_translation({5, 0, 0}) * C), AppliedCorrection{}, {kNow, 0, own});
  EXPECT_FALSE(off.apply);
  EXPECT_EQ(off.refusal, BadKind::kImplausible);
  EXPECT_NE(off.why.find("disagrees with the loop of keyframe 2"), std::string::npos) << off.why;
  // Without the keyframe's odometry pose (older than the tracker holds) there is nothing to check.
  EXPECT_TRUE(decide(with_loop(core::SE3::from_translation({5, 0, 0}) * C), AppliedCorrection{}, {kNow, 0, {}}).apply);
}

// The same entry on CVO_MAP_CORRECTION, of `revision` (of a back end started at `epoch`).
std::vector<std::uint8_t> correction_bytes(std::int64_t revision, const slam::MapSession& session,
                                           std::int64_t epoch = 0, std::vector<slam::SessionLoop> loops = {}) {
  return encode(
      to_message(slam::SessionCorrection{static_cast<std::uint64_t>(revision), session, std::move(loops)}, 1, epoch));
}

CorrectionDecision decide_correction(const std::vector<std::uint8_t>& bytes, const AppliedCorrection& last,
                                     const MapContext& context = {kNow, 0, {}}) {
  return decide_session_correction(bytes.data(), static_cast<int>(bytes.size()), kSession, last, kLimits, context);
}

// One decision: whatever a CVO_MAP with the session's entry is made to, the CVO_MAP_CORRECTION with
// that entry alone is made to as well (applied, or refused by the same kind).
TEST(MapDecision, ACorrectionAloneIsDecidedAsTheMapWithItsEntryIs) {
  AppliedCorrection placed_at_7{0, 7, kSession, true, kOneMetre, -1, std::nullopt, -1};
  placed_at_7.applied_utime = kNow - 1'000'000;
  struct Case {
    const char* what;
    std::int64_t revision, epoch;
    slam::MapSession entry;
    AppliedCorrection last;
    std::int64_t sender;
  };
  const auto at = [](double x) { return core::SE3::from_translation({x, 0, 0}); };
  const Case cases[] = {
      {"a first placement", 3, 0, placed(kSession, kOneMetre), AppliedCorrection{}, 0},
      {"a small move", 8, 0, placed(kSession, at(1.2)), placed_at_7, 0},
      {"stale", 6, 0, placed(kSession, at(1.2)), placed_at_7, 0},
      {"a jump", 8, 0, placed(kSession, at(3)), placed_at_7, 0},
      {"a revision leap", 7 + 1'000'000, 0, placed(kSession, kOneMetre), placed_at_7, 0},
      {"an epoch from the future", 1, kNow + 3600'000'000LL, placed(kSession, kOneMetre), placed_at_7, 0},
      {"another sender", 8, 0, placed(kSession, kOneMetre), placed_at_7, 6},
      {"unplaced within the epoch", 8, 0, test::map_session(kSession, false, kSession, 1, -1, {}), placed_at_7, 0},
      {"unplaced by a newer back end", 1, 5, test::map_session(kSession, false, kSession, 1, -1, {}), placed_at_7, 0},
  };
  int applied = 0;
  for (const auto& c : cases) {
    const MapContext context{kNow, c.sender, {}};
    const auto by_map = decide(map_bytes(c.revision, {placed(kOther, {}), c.entry}, c.epoch), c.last, context);
    const auto by_correction = decide_correction(correction_bytes(c.revision, c.entry, c.epoch), c.last, context);
    EXPECT_EQ(by_correction.apply, by_map.apply) << c.what << ": " << by_map.why << " / " << by_correction.why;
    EXPECT_FALSE(by_correction.ignored) << c.what;
    if (!by_map.apply) {
      EXPECT_EQ(by_correction.refusal, by_map.refusal) << c.what << ": " << by_correction.why;
      continue;
    }
    ++applied;
    EXPECT_EQ(by_correction.correction.revision, c.revision) << c.what;
    EXPECT_EQ(by_correction.correction.placed, by_map.correction.placed) << c.what;
    EXPECT_EQ(by_correction.correction.T_map_odom.translation(), by_map.correction.T_map_odom.translation()) << c.what;
  }
  EXPECT_EQ(applied, 3) << "a first placement, a small move, a newer back end's unplaced entry";
}

// Every tracker hears every session's corrections: another session's is no fault (not counted),
// whatever its order; and the word applied last, sent again (the back end re-sends corrections, a
// CVO_MAP repeats them), is ignored too, while another entry of the same revision is stale.
TEST(MapDecision, AnotherSessionsCorrectionAndTheAppliedOneAgainAreIgnored) {
  const auto others = decide_correction(correction_bytes(1, placed(kOther, kOneMetre)), AppliedCorrection{});
  EXPECT_FALSE(others.apply);
  EXPECT_TRUE(others.ignored) << others.why;
  const AppliedCorrection late{0, 9, kSession, true, kOneMetre, -1, std::nullopt, -1};
  EXPECT_TRUE(decide_correction(correction_bytes(2, placed(kOther, kOneMetre)), late).ignored) << "not stale: not ours";

  const auto first = decide_correction(correction_bytes(3, placed(kSession, kOneMetre)), AppliedCorrection{});
  ASSERT_TRUE(first.apply) << first.why;
  const auto again = decide_correction(correction_bytes(3, placed(kSession, kOneMetre)), first.correction);
  EXPECT_TRUE(again.ignored) << again.why;
  const auto as_map = decide(map_bytes(3, {placed(kOther, {}), placed(kSession, kOneMetre)}), first.correction);
  EXPECT_TRUE(as_map.ignored) << "the CVO_MAP of the applied revision: " << as_map.why;
  const auto other_entry =
      decide(map_bytes(3, {placed(kSession, core::SE3::from_translation({1.1, 0, 0}))}), first.correction);
  EXPECT_FALSE(other_entry.ignored);
  EXPECT_EQ(other_entry.refusal, BadKind::kStale) << other_entry.why;
  const auto from_another_sender =
      decide_correction(correction_bytes(3, placed(kSession, kOneMetre)), first.correction, {kNow, 6, {}});
  EXPECT_FALSE(from_another_sender.ignored) << "a repeat only from the sender applied";
}

// A first placement by a correction is checked against the loops it carries, each with the other
// keyframe's map pose: C · O_a = M_b · (T_a^b)⁻¹ up to the jump bound.
TEST(MapDecision, AFirstPlacementByACorrectionAgreesWithItsLoops) {
  const core::SE3 O_a = core::SE3::from_translation({0.3, 0, 0});
  const core::SE3 M_b = core::SE3::from_translation({5, 1, 0});
  const core::SE3 T_ab = core::SE3::from_translation({0.2, 0, 0.1});
  const core::SE3 C = M_b * T_ab.inverse() * O_a.inverse();
  const std::vector<slam::SessionLoop> loops{{2, kOther, 4, T_ab, M_b}};
  const OwnKeyframe own[] = {{1, {}}, {2, O_a}};
  EXPECT_TRUE(decide_correction(correction_bytes(3, placed(kSession, C), 0, loops), {}, {kNow, 0, own}).apply);
  const auto off = decide_correction(
      correction_bytes(3, placed(kSession, core::SE3::from_translation({5, 0, 0}) * C), 0, loops), {}, {kNow, 0, own});
  EXPECT_FALSE(off.apply);
  EXPECT_EQ(off.refusal, BadKind::kImplausible);
  EXPECT_NE(off.why.find("disagrees with the loop of keyframe 2"), std::string::npos) << off.why;
}

// A correction of `revision` (of a back end started at `epoch`) for `session`'s entry, that says the
// back end holds keyframes below a million: a forger's, on an open bus, wanting the spool deleted.
std::vector<std::uint8_t> acknowledging_a_million(std::int64_t revision, const slam::MapSession& session,
                                                  std::int64_t epoch = 0) {
  return encode(
      to_message(slam::SessionCorrection{static_cast<std::uint64_t>(revision), session, {}}, 1, epoch, 1'000'000));
}

// Issue 48: the tracker deletes from its spool what a correction acknowledges, so only a word it
// applies (or the applied one again, from its sender) acknowledges anything; one the sender, epoch
// or plausibility rules refuse acknowledges nothing.
TEST(MapDecision, OnlyACorrectionTheTrackerAppliesAcknowledgesAnything) {
  AppliedCorrection last{0, 7, kSession, true, kOneMetre, -1, std::nullopt, -1};
  last.applied_utime = kNow - 1'000'000;
  const std::int64_t in_a_year = kNow + 365LL * 86400 * 1'000'000;
  struct Case {
    const char* what;
    std::int64_t revision, epoch, sender;
    core::SE3 correction;
  };
  const Case refused[] = {{"an epoch from the future", 1, in_a_year, 0, kOneMetre},
                          {"stale", 6, 0, 0, kOneMetre},
                          {"a revision leap", 7 + 1'000'000, 0, 0, kOneMetre},
                          {"another sender within the epoch", 8, 0, 6, kOneMetre},
                          {"a jump of 9 m", 8, 0, 0, core::SE3::from_translation({10, 0, 0})}};
  for (const auto& c : refused) {
    const auto d = decide_correction(acknowledging_a_million(c.revision, placed(kSession, c.correction), c.epoch), last,
                                     {kNow, c.sender, {}});
    EXPECT_FALSE(d.apply || d.ignored) << c.what;
    EXPECT_EQ(d.acknowledged, std::nullopt) << c.what << ": " << d.why;
  }
  const auto applied = decide_correction(acknowledging_a_million(8, placed(kSession, kOneMetre)), last);
  ASSERT_TRUE(applied.apply) << applied.why;
  EXPECT_EQ(applied.acknowledged, std::pair(kSession, std::int64_t{1'000'000}));
  const auto again = decide_correction(acknowledging_a_million(8, placed(kSession, kOneMetre)), applied.correction);
  ASSERT_TRUE(again.ignored) << again.why;
  EXPECT_EQ(again.acknowledged, std::pair(kSession, std::int64_t{1'000'000})) << "the back end re-sends its word";
}

// Another session's correction (one the tracker handed over from its spool, say) is ignored, and
// acknowledges only when it may come from the back end whose word was applied, or a newer one:
// not an older epoch, one from the future, a revision leap or another sender within the epoch.
TEST(MapDecision, AnotherSessionsCorrectionAcknowledgesOnlyUnderTheEpochAndSenderRules) {
  AppliedCorrection last{5, 7, kSession, true, kOneMetre, -1, std::nullopt, -1};
  last.applied_utime = kNow - 1'000'000;
  const auto others = [&](std::int64_t revision, std::int64_t epoch, std::int64_t sender) {
    return decide_correction(acknowledging_a_million(revision, placed(kOther, kOneMetre), epoch), last,
                             {kNow, sender, {}});
  };
  struct Case {
    const char* what;
    std::int64_t revision, epoch, sender;
    BadKind kind;
  };
  const Case refused[] = {{"an older back end", 9, 4, 0, BadKind::kStale},
                          {"an epoch from the future", 1, kNow + 3600'000'000LL, 0, BadKind::kImplausible},
                          {"a revision leap", 7 + 1'000'000, 5, 0, BadKind::kImplausible},
                          {"another sender within the epoch", 8, 5, 6, BadKind::kConflict}};
  for (const auto& c : refused) {
    const auto d = others(c.revision, c.epoch, c.sender);
    EXPECT_TRUE(d.ignored) << c.what << ": not this session's word, nothing to refuse of it";
    EXPECT_EQ(d.acknowledged, std::nullopt) << c.what;
    EXPECT_EQ(d.acknowledgement_refused, kOther) << c.what;
    EXPECT_EQ(d.refusal, c.kind) << c.what << ": " << d.why;
  }
  const Case trusted[] = {{"an earlier revision of the applied epoch", 3, 5, 0, {}},
                          {"a later one", 9, 5, 0, {}},
                          {"a newer back end", 1, 6, 6, {}}};
  for (const auto& c : trusted) {
    const auto d = others(c.revision, c.epoch, c.sender);
    EXPECT_TRUE(d.ignored) << c.what;
    EXPECT_EQ(d.acknowledged, std::pair(kOther, std::int64_t{1'000'000})) << c.what << ": " << d.why;
    EXPECT_EQ(d.acknowledgement_refused, std::nullopt) << c.what;
  }
}

// What the tracker cannot use of a correction is refused whole by its kind: more loops than
// MAX_LOOPS, a loop's pose that is no rigid transform, a correction that is not finite.
TEST(MapDecision, AnUnusableCorrectionIsRefusedByKind) {
  auto many = to_message(slam::SessionCorrection{3, placed(kSession, kOneMetre), {}}, 1, 0);
  const cvo_lcm::map_correction_loop_t loop{1, kOther, 2, to_message(kOneMetre), to_message(core::SE3())};
  many.loops.assign(cvo_lcm::map_correction_t::MAX_LOOPS + 1, loop);
  many.num_loops = static_cast<std::int32_t>(many.loops.size());
  const auto too_many = decide_correction(encode(many), {});
  EXPECT_EQ(too_many.refusal, BadKind::kContent) << too_many.why;
  EXPECT_NE(too_many.why.find("more than 8"), std::string::npos) << too_many.why;
  auto bent = to_message(slam::SessionCorrection{3, placed(kSession, kOneMetre), {{2, kOther, 4, {}, {}}}}, 1, 0);
  bent.loops[0].other_pose.orientation[0] = 3;  // not a unit quaternion
  EXPECT_EQ(decide_correction(encode(bent), {}).refusal, BadKind::kContent);
  auto nan = to_message(slam::SessionCorrection{3, placed(kSession, kOneMetre), {}}, 1, 0);
  nan.session.correction.position[2] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(decide_correction(encode(nan), {}).refusal, BadKind::kNotFinite);
  // Converted back, a usable one is what was sent; at most MAX_LOOPS loops go.
  std::vector<slam::SessionLoop> ten(10, {2, kOther, 4, kOneMetre, {}});
  const auto sent = to_message(slam::SessionCorrection{3, placed(kSession, kOneMetre), ten}, 1, 0);
  EXPECT_EQ(sent.num_loops, cvo_lcm::map_correction_t::MAX_LOOPS);
  std::string error;
  const auto back = from_message(sent, &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->revision, 3u);
  EXPECT_EQ(back->session.session, kSession);
  EXPECT_EQ(back->loops.size(), 8u);
  EXPECT_EQ(back->loops[0].measurement.translation(), kOneMetre.translation());
}

}  // namespace
}  // namespace cvo::lcm
