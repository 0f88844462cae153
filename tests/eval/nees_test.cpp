#include "libcvo/eval/nees.hpp"

#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "eval/test_trajectories.hpp"

namespace cvo::eval {
namespace {

using testing::helix;
using testing::make;

// A covariance with correlations between every pair of axes, as a registration's.
core::Matrix6d correlated_covariance() {
  core::Matrix6d A;
  A << 2, 1, 0, 0, 0.5, 0, 0, 3, 1, 0, 0, 0.2, 0, 0, 1, 0.3, 0, 0, 0, 0, 0, 1, 0.4, 0, 0.1, 0, 0, 0, 2, 0.6, 0, 0.3, 0,
      0, 0, 1;
  return 1e-6 * (A * A.transpose() + core::Matrix6d::Identity());
}

std::vector<core::Vector6d> gaussian_samples(const core::Matrix6d& sigma, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  const core::Matrix6d L = Eigen::LLT<core::Matrix6d>(sigma).matrixL();
  std::vector<core::Vector6d> out;
  for (int k = 0; k < n; ++k) {
    core::Vector6d z;
    for (int i = 0; i < 6; ++i) z[i] = normal(rng);
    out.push_back(L * z);
  }
  return out;
}

double mean_nees(const std::vector<core::Vector6d>& errors, const core::Matrix6d& claimed) {
  double sum = 0;
  for (const auto& e : errors) sum += nees(e, claimed)->nees;
  return sum / static_cast<double>(errors.size());
}

TEST(Nees, ConsistentGaussianErrorsAverageSixThreeOfThemEachPart) {
  const auto sigma = correlated_covariance();
  const auto errors = gaussian_samples(sigma, 20000, 1);
  EXPECT_NEAR(mean_nees(errors, sigma), 6.0, 0.15);
  double t = 0, r = 0;
  for (const auto& e : errors) t += nees(e, sigma)->translation, r += nees(e, sigma)->rotation;
  EXPECT_NEAR(t / 20000, 3.0, 0.1);
  EXPECT_NEAR(r / 20000, 3.0, 0.1);
}

TEST(Nees, AnOverConfidentCovarianceShowsFarAboveSix) {
  const auto sigma = correlated_covariance();
  const auto errors = gaussian_samples(sigma, 20000, 2);
  EXPECT_NEAR(mean_nees(errors, sigma / 10), 60.0, 2.0);
  EXPECT_NEAR(mean_nees(errors, sigma * 4), 1.5, 0.05);
}

TEST(Nees, ASingularCovarianceHasNone) {
  EXPECT_FALSE(nees(core::Vector6d::Ones(), core::Matrix6d::Zero()).has_value());
}

// An estimate whose every relative pose errs by a sample ξ_n on the right: B = Â exp(ξ_n).
TEST(Nees, RelativePosesOfAnEstimateWithGaussianErrorsAverageSix) {
  const auto gt = make(801, helix);
  const auto sigma = correlated_covariance();
  const auto errors = gaussian_samples(sigma, 800, 3);
  core::Trajectory est{gt.front()};
  std::vector<io::StampedCovariance> covariances;
  for (std::size_t n = 1; n < gt.size(); ++n) {
    const core::SE3 truth = gt[n - 1].pose.inverse() * gt[n].pose;
    est.push_back({gt[n].timestamp, est.back().pose * truth * core::SE3::exp(-errors[n - 1])});
    covariances.push_back({gt[n].timestamp, sigma});
  }
  const NeesResult r = relative_pose_nees(gt, est, covariances, {.max_difference = 0.2});
  EXPECT_EQ(r.pairs.size(), 800u);
  EXPECT_NEAR(r.nees.mean, 6.0, 0.6);
  EXPECT_NEAR(r.translation.mean + r.rotation.mean, 6.0, 0.8);
}

TEST(Nees, GroundTruthIsInterpolatedAtTheEstimateStamps) {
  // Ground truth at 1/8 s, estimate exact at the midpoints: NEES is zero only with interpolation.
  const auto gt = make(20, [](double t) { return core::SE3::from_translation({t * t, 0, 0}); });
  core::Trajectory est;
  std::vector<io::StampedCovariance> covariances;
  for (int k = 0; k < 10; ++k) {
    const double t = 0.5 * testing::kStep + testing::kStep * k;
    const core::SE3 a = gt[static_cast<std::size_t>(k)].pose, b = gt[static_cast<std::size_t>(k) + 1].pose;
    est.push_back({t, core::interpolate(a, b, 0.5)});
    if (k > 0) covariances.push_back({t, 1e-6 * core::Matrix6d::Identity()});
  }
  const NeesResult r = relative_pose_nees(gt, est, covariances, {.max_difference = 0.2});
  EXPECT_EQ(r.pairs.size(), 9u);
  EXPECT_LT(r.nees.max, 1e-12);
}

TEST(Nees, PairsWithoutGroundTruthOrAPreviousPoseAreLeftOutAndNoneLeftThrows) {
  const auto gt = make(10, helix);
  const std::vector<io::StampedCovariance> covariances{
      {gt.front().timestamp, core::Matrix6d::Identity()},  // no previous pose
      {99.0, core::Matrix6d::Identity()}};                 // no estimate at this stamp
  EXPECT_THROW(relative_pose_nees(gt, gt, covariances), std::invalid_argument);
}

}  // namespace
}  // namespace cvo::eval
