// Consecutive real frames of TUM fr1/rpy against the ground-truth relative motion.
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>

#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/registration/point_selection.hpp"
#include "libcvo/registration/registration.hpp"
#include "tests/registration/registration_fixtures.hpp"

namespace cvo::registration {
namespace {

core::SE3 groundtruth_at(const core::Trajectory& gt, double t) {
  const auto it = std::lower_bound(gt.begin(), gt.end(), t, [](const auto& p, double v) { return p.timestamp < v; });
  if (it == gt.begin()) return gt.front().pose;
  if (it == gt.end()) return gt.back().pose;
  const auto& a = *(it - 1);
  const auto& b = *it;
  return core::interpolate(a.pose, b.pose, (t - a.timestamp) / (b.timestamp - a.timestamp));
}

struct Errors {
  std::vector<double> translation_mm, rotation_deg;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
double maximum(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }

// Frame-to-frame registration of `pairs` consecutive pairs, each from the previous estimate
// (constant velocity), as the tracker does.
Errors register_consecutive(const std::filesystem::path& dir, std::size_t pairs) {
  auto sequence = io::TumSequence::open(dir);
  const auto& gt = sequence.groundtruth();
  PointSelector selector(sequence.intrinsics().width, sequence.intrinsics().height, core::SelectionParameters{});
  Registration registration(Capacities{8192}, core::CvoParameters{});
  PointCloud previous(8192), current(8192);
  core::SE3 velocity;
  double previous_time = 0;
  Errors errors;
  for (std::size_t n = 0; n <= pairs; ++n) {
    const auto frame = sequence.next();
    if (!frame) break;
    EXPECT_EQ(selector.select(*frame, current).status, SelectionStatus::kOk);
    if (n > 0) {
      const auto r = registration.align(previous, current, velocity);
      EXPECT_TRUE(r.converged) << "pair " << n << ": " << to_string(r.status);
      const auto truth = groundtruth_at(gt, previous_time).inverse() * groundtruth_at(gt, frame->timestamp);
      const auto e = truth.inverse() * r.transform;
      errors.translation_mm.push_back(1e3 * e.translation().norm());
      errors.rotation_deg.push_back(testing::deg(e.angle()));
      velocity = r.transform;
    }
    std::swap(previous, current);
    previous_time = frame->timestamp;
  }
  return errors;
}

void report_and_check(const Errors& e, std::size_t expected_pairs) {
  ASSERT_EQ(e.translation_mm.size(), expected_pairs);
  const double mt = median(e.translation_mm), xt = maximum(e.translation_mm);
  const double mr = median(e.rotation_deg), xr = maximum(e.rotation_deg);
  std::printf("%zu pairs: translation median %.2f mm, max %.2f mm; rotation median %.3f deg, max %.3f deg\n",
              expected_pairs, mt, xt, mr, xr);
  ::testing::Test::RecordProperty("translation_median_mm", std::to_string(mt));
  ::testing::Test::RecordProperty("rotation_median_deg", std::to_string(mr));
  // Measured on fr1/rpy frames 0-50: medians ~3.5 mm / 0.34°, maxima ~20 mm / 1.0° (the camera
  // moves ~3 mm and ~2.3° per frame; the ground truth itself is good to ~1 mm). Bounds at about
  // twice that, so a regression in the solver or the selection shows.
  EXPECT_LT(mt, 8.0);
  EXPECT_LT(mr, 0.7);
  EXPECT_LT(xt, 40.0);
  EXPECT_LT(xr, 2.0);
}

TEST(RealFrames, CommittedSampleFortyNinePairs) {
  report_and_check(register_consecutive(std::filesystem::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50", 49), 49);
}

TEST(RealFrames, SharedFr1RpyFiftyPairs) {
  const auto dir = std::filesystem::path(CVO_SHARED_DATA_DIR) / "tum" / "fr1_rpy";
  if (!std::filesystem::exists(dir / "rgb.txt")) GTEST_SKIP() << "shared data absent: " << dir;
  report_and_check(register_consecutive(dir, 50), 50);
}

// The points of a white room: every label alike, so the colour kernel keeps every fixed point
// within reach and the geometry alone registers (the worst case of a texture-less scene).
PointCloud with_one_colour(const PointCloud& cloud) {
  PointCloud out(cloud.capacity());
  for (std::size_t i = 0; i < cloud.size(); ++i) out.push_back(cloud.position(i), Feature{0.8f, 0.8f, 0.8f, 0, 0});
  return out;
}

// Where every colour is alike a point at a desk's distance has many more candidates than the
// budget of 32: it sums a systematic sample of them, weighted by what each stands for
// (registration.hpp, "The pair budget"). The sums then cost at most 32 pairs a point whatever the
// colours, and the estimate stays within a fraction of a millimetre of a search every iteration,
// which sums them all. Consecutive real frames (the committed sample), labels made alike, the
// tracker's guess (the motion of the pair before).
// Measured over 9 pairs: at most 0.74 mm and 0.041° apart, 2.5 times fewer pairs (asserted: 1.5 mm,
// 0.1°, 2 times).
TEST(RealFrames, PairBudgetBoundsTheCostWhereEveryColourIsAlike) {
  auto sequence = io::TumSequence::open(std::filesystem::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50");
  PointSelector selector(sequence.intrinsics().width, sequence.intrinsics().height, core::SelectionParameters{});
  const core::CvoParameters parameters;
  Registration searched(Capacities{8192, 0}, parameters), budget(Capacities{8192, 32}, parameters);
  PointCloud selected(8192), previous(8192);
  core::SE3 velocity;
  double worst_mm = 0, worst_deg = 0;
  std::size_t searched_pairs = 0, budget_pairs = 0;
  for (int n = 0; n < 10; ++n) {
    const auto frame = sequence.next();
    ASSERT_TRUE(frame);
    selector.select(*frame, selected);
    PointCloud current = with_one_colour(selected);
    if (n > 0) {
      const auto a = searched.align(previous, current, velocity);
      const auto b = budget.align(previous, current, velocity);
      ASSERT_TRUE(a.converged && b.converged) << "pair " << n;
      EXPECT_EQ(budget.full_searches(), 0u);
      for (std::size_t i = 0; i < budget.pairs_logged(); ++i) {
        EXPECT_LE(budget.pairs_per_iteration()[i], 32 * current.size()) << "pair " << n << ", iteration " << i;
        budget_pairs += budget.pairs_per_iteration()[i];
      }
      for (std::size_t i = 0; i < searched.pairs_logged(); ++i) searched_pairs += searched.pairs_per_iteration()[i];
      const auto d = a.transform.inverse() * b.transform;
      worst_mm = std::max(worst_mm, 1e3 * d.translation().norm());
      worst_deg = std::max(worst_deg, testing::deg(d.angle()));
      velocity = a.transform;
    }
    previous = std::move(current);
  }
  std::printf("budget against a search every iteration: at most %.3f mm, %.4f deg apart; pairs %zu against %zu\n",
              worst_mm, worst_deg, budget_pairs, searched_pairs);
  EXPECT_LT(worst_mm, 1.5);
  EXPECT_LT(worst_deg, 0.1);
  EXPECT_LT(2 * budget_pairs, searched_pairs);
}

}  // namespace
}  // namespace cvo::registration
