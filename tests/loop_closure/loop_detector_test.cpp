// The loop detector end to end: bag-of-words candidates, verification, update_poses, on real
// keyframes and on a rendered orbit that returns to its start.
#include "libcvo/loop_closure/loop_detector.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loop_closure/loop_test_frames.hpp"

namespace cvo::loop_closure {
namespace {

using Clock = std::chrono::steady_clock;

class LoopDetectorTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { vocabulary_ = Vocabulary::load(CVO_DEFAULT_VOCABULARY); }
  static void TearDownTestSuite() { vocabulary_.reset(); }
  static LoopDetector detector() { return LoopDetector(*vocabulary_, LoopDetectorParameters{}); }

  // add_keyframe, timed.
  std::vector<LoopClosure> add(LoopDetector& d, std::int64_t id, const testing::TestKeyframe& k,
                               const core::SE3& pose) {
    const auto start = Clock::now();
    auto loops = d.add_keyframe(id, k.frame, k.cloud, pose);
    times_ms_.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
    return loops;
  }
  void print_times(const char* what) const {
    double sum = 0;
    for (const double t : times_ms_) sum += t;
    std::printf("%s: add_keyframe mean %.1f ms, max %.1f ms over %zu keyframes\n", what,
                sum / static_cast<double>(times_ms_.size()), *std::max_element(times_ms_.begin(), times_ms_.end()),
                times_ms_.size());
  }

 private:
  static inline std::optional<Vocabulary> vocabulary_;
  std::vector<double> times_ms_;
};

void print_attempts(std::int64_t id, const LoopDetector& d) {
  for (const auto& a : d.last_attempts())
    std::printf("  keyframe %lld vs %lld: eta %.2f, %d matches, %d inliers, alpha %.4f: %s\n",
                static_cast<long long>(id), static_cast<long long>(a.candidate), a.eta, a.matches, a.inliers, a.alpha,
                a.verdict);
}

// Keyframes: fr1/rpy frames 20 (id 0) and 44 (id 1), then frame 28 (id 2): the previous keyframe
// is id 1, so id 0, 8 frames (16°) away, is the candidate.
TEST_F(LoopDetectorTest, FindsARevisitedRealViewAmongEarlierKeyframes) {
  const std::vector<std::size_t> frames{20, 44, 28};
  std::vector<testing::TestKeyframe> k;
  for (const auto f : frames) k.push_back(testing::real_keyframe(f));
  const auto pose = [&](std::size_t n) { return testing::drifted(k[n].truth, static_cast<double>(n) / 2); };

  LoopDetector d = detector();
  EXPECT_TRUE(add(d, 0, k[0], pose(0)).empty());
  EXPECT_TRUE(d.last_attempts().empty());
  EXPECT_TRUE(add(d, 1, k[1], pose(1)).empty());  // only keyframe 0 before it, the previous one
  const auto loops = add(d, 2, k[2], pose(2));
  print_attempts(2, d);
  print_times("fr1");
  EXPECT_EQ(d.size(), 3u);
  for (const auto& a : d.last_attempts()) EXPECT_NE(a.candidate, 1);  // the previous keyframe
  ASSERT_EQ(loops.size(), 1u);
  const LoopClosure& loop = loops.front();
  EXPECT_EQ(loop.from, 0);
  EXPECT_EQ(loop.to, 2);
  EXPECT_GT(loop.eta, LoopDetectorParameters{}.loop.similarity_threshold);
  EXPECT_GT(loop.alpha, 0.0);
  const auto e = testing::pose_error(loop.measurement, k[0].truth.inverse() * k[2].truth);
  std::printf("loop 0 -> 2 (frames 20 -> 28): error %.1f mm, %.2f deg\n", 1e3 * e.translation_m, e.rotation_deg);
  EXPECT_LT(e.translation_m, 0.03);
  EXPECT_LT(e.rotation_deg, 2.0);

  // update_poses reaches the α test: with keyframe 0's estimate moved so that the trajectory
  // already holds the loop's pose, the estimate is that pose and no rival of it; the loop stands
  // on the identity and RANSAC's pose (ids not stored are ignored).
  LoopDetector again = detector();
  add(again, 0, k[0], pose(0));
  add(again, 1, k[1], pose(1));
  again.update_poses({{0, pose(2) * loop.measurement.inverse()}, {99, core::SE3()}});
  const auto same = add(again, 2, k[2], pose(2));
  ASSERT_EQ(again.last_attempts().size(), 1u);
  EXPECT_EQ(d.last_attempts().front().rivals, 3);
  EXPECT_EQ(again.last_attempts().front().rivals, 2);
  EXPECT_EQ(same.size(), 1u);

  EXPECT_THROW(d.add_keyframe(2, k[0].frame, k[0].cloud, pose(0)), std::invalid_argument);  // ids must increase
}

// Two sessions (slam/mapper.hpp): frames 20 and 44 are session A's keyframes; session B's first
// keyframe (frame 28) has no predecessor in its session, so no η and no candidates; its second
// (frame 27, previous = B's first) finds A's frame 20. B is a piece of its own: its estimate says
// nothing about A's, and the α test leaves the trajectory term out (an estimate of another piece
// is no rival, however far off).
TEST_F(LoopDetectorTest, ASessionsFirstKeyframeHasNoCandidatesAndPiecesAreNotCompared) {
  std::vector<testing::TestKeyframe> k;
  for (const std::size_t f : {20, 44, 28, 27}) k.push_back(testing::real_keyframe(f));
  LoopDetector d = detector();
  d.add_keyframe({0, std::nullopt, k[0].truth, 0}, k[0].frame, k[0].cloud);
  d.add_keyframe({1, 0, k[1].truth, 0}, k[1].frame, k[1].cloud);
  EXPECT_TRUE(d.add_keyframe({100, std::nullopt, core::SE3(), 1}, k[2].frame, k[2].cloud).empty());
  EXPECT_TRUE(d.last_attempts().empty());
  const auto loops = d.add_keyframe({101, 100, core::SE3(), 1}, k[3].frame, k[3].cloud);
  print_attempts(101, d);
  ASSERT_EQ(loops.size(), 1u);
  EXPECT_EQ(loops.front().from, 0);
  EXPECT_EQ(loops.front().to, 101);

  // An estimate 5 cm off the loop's pose: inside one piece it is a rival of the CVO pose; in
  // another piece the two poses are not comparable, the estimate is no term of α, and the loop
  // keeps the α of CVO against identity and RANSAC.
  const core::SE3 b_pose = k[0].truth * loops.front().measurement * core::SE3::from_translation({0.05, 0, 0});
  const auto attempt_in_piece = [&](std::int64_t piece) {
    LoopDetector e = detector();
    e.add_keyframe({0, std::nullopt, k[0].truth, 0}, k[0].frame, k[0].cloud);
    e.add_keyframe({1, 0, k[1].truth, 0}, k[1].frame, k[1].cloud);
    e.add_keyframe({100, std::nullopt, b_pose, piece}, k[2].frame, k[2].cloud);
    e.add_keyframe({101, 100, b_pose, piece}, k[3].frame, k[3].cloud);
    for (const auto& a : e.last_attempts())
      if (a.candidate == 0) return a;
    return LoopAttempt{};
  };
  EXPECT_EQ(attempt_in_piece(0).rivals, 3);
  EXPECT_EQ(attempt_in_piece(1).rivals, 2);
  EXPECT_NEAR(attempt_in_piece(1).alpha, loops.front().alpha, 1e-9);
  EXPECT_GT(loops.front().alpha, 1e-3);
  EXPECT_THROW(d.add_keyframe({101, 100, b_pose, 1}, k[3].frame, k[3].cloud), std::invalid_argument);  // stored already
}

// max_refinements caps the CVO refinements (the back end's main cost) per new keyframe; candidates
// refused before CVO (matches, RANSAC) do not count, and the best η go first.
TEST_F(LoopDetectorTest, RefinesAtMostMaxRefinementsCandidatesBestEtaFirst) {
  const std::vector<std::size_t> frames{10, 13, 16, 19, 22, 40, 14};
  std::vector<testing::TestKeyframe> k;
  for (const auto f : frames) k.push_back(testing::real_keyframe(f));
  const auto refined = [](const LoopAttempt& a) {
    const std::string verdict = a.verdict;
    return verdict != "too few matches" && verdict != "RANSAC failed";
  };
  const auto run = [&](int max_refinements) {
    LoopDetectorParameters parameters;
    parameters.verification.max_refinements = max_refinements;
    LoopDetector d(Vocabulary::load(CVO_DEFAULT_VOCABULARY), parameters);
    for (std::size_t n = 0; n < k.size(); ++n)
      d.add_keyframe(static_cast<std::int64_t>(n), k[n].frame, k[n].cloud, k[n].truth);
    print_attempts(static_cast<std::int64_t>(k.size() - 1), d);
    return d.last_attempts();
  };
  const auto all = run(0);
  const auto capped = run(2);
  const auto count = [&](const std::vector<LoopAttempt>& attempts) {
    return std::count_if(attempts.begin(), attempts.end(), refined);
  };
  ASSERT_GT(count(all), 2);  // frame 14 overlaps 10-22: more than two candidates reach CVO
  EXPECT_EQ(count(capped), 2);
  // The capped run tried the uncapped one's attempts in the same order, up to its second refinement.
  ASSERT_LE(capped.size(), all.size());
  for (std::size_t n = 0; n < capped.size(); ++n) {
    EXPECT_EQ(capped[n].candidate, all[n].candidate);
    EXPECT_STREQ(capped[n].verdict, all[n].verdict);
    if (n > 0) {
      EXPECT_GE(capped[n - 1].eta, capped[n].eta);
    }
  }
  EXPECT_TRUE(refined(capped.back()));
}

// The textured room's orbit turns the camera a full 360° in 12 s and returns to its start pose.
// Keyframes every second (30° apart), then two closing ones at 11.3 s and 11.65 s, 10° and 5°
// short of the start. The estimates drift by up to 5 cm and 3° over the lap, as odometry would.
// The closing keyframes must close the loop with the first ones, and every accepted loop must
// match the exact ground truth.
TEST_F(LoopDetectorTest, ClosesTheLoopOfARenderedOrbitWithTheExactRelativePose) {
  std::vector<double> stamps;
  for (int s = 0; s < 12; ++s) stamps.push_back(s);
  stamps.push_back(11.3);
  stamps.push_back(11.65);
  const double period = sim::path_period(sim::PathKind::orbit);

  LoopDetector d = detector();
  std::vector<testing::TestKeyframe> k;
  std::vector<LoopClosure> all;
  int closing = 0;
  for (std::size_t n = 0; n < stamps.size(); ++n) {
    k.push_back(testing::rendered_keyframe(stamps[n]));
    const auto loops = add(d, static_cast<std::int64_t>(n), k[n], testing::drifted(k[n].truth, stamps[n] / period));
    print_attempts(static_cast<std::int64_t>(n), d);
    all.insert(all.end(), loops.begin(), loops.end());
    if (stamps[n] > 11.0)  // to keyframe 0 or 1 (5-40° away)
      closing += static_cast<int>(std::count_if(loops.begin(), loops.end(), [](const auto& l) { return l.from <= 1; }));
  }
  print_times("orbit");
  EXPECT_GE(closing, 1);
  for (const auto& loop : all) {
    const auto truth =
        k[static_cast<std::size_t>(loop.from)].truth.inverse() * k[static_cast<std::size_t>(loop.to)].truth;
    const auto e = testing::pose_error(loop.measurement, truth);
    std::printf("loop %lld -> %lld: eta %.2f, alpha %.4f, %d inliers, error %.2f mm, %.3f deg\n",
                static_cast<long long>(loop.from), static_cast<long long>(loop.to), loop.eta, loop.alpha, loop.inliers,
                1e3 * e.translation_m, e.rotation_deg);
    // Seen: under 5 mm and 0.2°; the rendered depth is exact up to Kinect-like noise.
    EXPECT_LT(e.translation_m, 0.01);
    EXPECT_LT(e.rotation_deg, 0.3);
  }
}

}  // namespace
}  // namespace cvo::loop_closure
