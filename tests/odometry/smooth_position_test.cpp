#include "libcvo/odometry/smooth_position.hpp"

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace cvo::odometry {
namespace {

// A camera on a path (position and orientation at t), tracked at 30 Hz with white position noise
// of standard deviation `sigma` (m) along its own x, y, z axes: what the filter is given, the
// tracked relative pose's translation covariance being twice the noise's (two poses' errors).
struct FilterRun {
  std::vector<Eigen::Vector3d> truth, tracked, smooth;
  std::vector<core::Matrix6d> published;  // the relative covariances, from the third frame on
  std::vector<Eigen::Matrix3d> rotations;
};

template <class Path>
FilterRun run(const Path& path, const Eigen::Vector3d& sigma, int frames, std::uint32_t seed = 1) {
  std::mt19937 random(seed);
  std::normal_distribution<double> gauss;
  SmoothPosition filter;
  core::Matrix6d relative = core::Matrix6d::Identity() * 1e-6;  // rotation block: any
  relative.topLeftCorner<3, 3>() = 2 * sigma.cwiseProduct(sigma).asDiagonal();
  FilterRun r;
  for (int i = 0; i < frames; ++i) {
    const double t = i / 30.0;
    const auto [p, R] = path(t);
    const Eigen::Vector3d noise(sigma.x() * gauss(random), sigma.y() * gauss(random), sigma.z() * gauss(random));
    const core::SE3 tracked(R, p + R * noise);
    const SmoothStep s = smooth(filter, 1000.0 + t, tracked, i == 0 ? std::nullopt : std::optional(relative));
    EXPECT_TRUE(s.pose.rotation().isApprox(tracked.rotation())) << "rotation passes through";
    r.truth.push_back(p);
    r.tracked.push_back(tracked.translation());
    r.smooth.push_back(s.pose.translation());
    r.rotations.push_back(R);
    if (i >= 3) {
      EXPECT_TRUE(s.relative.has_value());
      r.published.push_back(*s.relative);
    }
  }
  return r;
}

// RMS of the one-frame error (estimated step minus true step), from frame `from` on.
double one_frame_rms(const std::vector<Eigen::Vector3d>& estimate, const std::vector<Eigen::Vector3d>& truth,
                     std::size_t from = 10) {
  double sum = 0;
  for (std::size_t i = from; i < truth.size(); ++i)
    sum += ((estimate[i] - estimate[i - 1]) - (truth[i] - truth[i - 1])).squaredNorm();
  return std::sqrt(sum / static_cast<double>(truth.size() - from));
}

double position_rms(const std::vector<Eigen::Vector3d>& estimate, const std::vector<Eigen::Vector3d>& truth) {
  double sum = 0;
  for (std::size_t i = 10; i < truth.size(); ++i) sum += (estimate[i] - truth[i]).squaredNorm();
  return std::sqrt(sum / static_cast<double>(truth.size() - 10));
}

// A robot's smooth drive: a 1 m circle at 0.3 m/s, the camera turning with it.
std::pair<Eigen::Vector3d, Eigen::Matrix3d> circle(double t) {
  const double a = 0.3 * t;
  return {Eigen::Vector3d(std::cos(a), std::sin(a), 0.5),
          Eigen::AngleAxisd(a + M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix()};
}

// A shaken hand: 2 cm at 2 Hz (accelerations of 3 m/s², a frame's noise every few frames).
std::pair<Eigen::Vector3d, Eigen::Matrix3d> shaken(double t) {
  return {Eigen::Vector3d(0.02 * std::sin(4 * M_PI * t), 0.01 * std::cos(6 * M_PI * t), 0.2 * t),
          Eigen::AngleAxisd(0.5 * std::sin(2 * M_PI * t), Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix()};
}

// One-frame and position errors, tracked and published, of a run.
struct Errors {
  double one_frame_tracked, one_frame_published, position_tracked, position_published;
};
Errors errors_of(const FilterRun& r, const char* name) {
  const Errors e{one_frame_rms(r.tracked, r.truth), one_frame_rms(r.smooth, r.truth), position_rms(r.tracked, r.truth),
                 position_rms(r.smooth, r.truth)};
  std::printf("%s: one-frame error %.2f mm tracked, %.2f mm published; position %.2f / %.2f mm\n", name,
              1e3 * e.one_frame_tracked, 1e3 * e.one_frame_published, 1e3 * e.position_tracked,
              1e3 * e.position_published);
  return e;
}

TEST(SmoothPosition, OnASmoothDriveItSmoothsTheOneFrameErrorAndKeepsThePosition) {
  const Errors e = errors_of(run(circle, Eigen::Vector3d(0.001, 0.002, 0.004), 600), "smooth drive");
  EXPECT_LT(e.one_frame_published, 0.8 * e.one_frame_tracked);  // σ_a² holds the noise too: a bound (the header)
  EXPECT_LT(e.position_published, e.position_tracked);
}

// The acceleration variance is measured from what the filter sees: a camera that shakes gets a
// filter that follows it (no lag beyond the noise) and still smooths what is noise.
TEST(SmoothPosition, FollowsAShakenCamera) {
  const Errors e = errors_of(run(shaken, Eigen::Vector3d(0.0005, 0.0005, 0.001), 600), "shaken camera");
  EXPECT_LT(e.one_frame_published, e.one_frame_tracked);
  EXPECT_LT(e.position_published, 1.5 * e.position_tracked);
}

// The published translation covariance is the smooth increment's, in frame n's axes (the noise is
// anisotropic along the camera's axes, the camera turning): its NEES is within a factor three of 3,
// on the safe side (the filter takes the tracked increment's covariance, twice a position's, as
// its measurement noise, as it must where the tracked errors are not white).
TEST(SmoothPosition, ThePublishedCovarianceIsTheSmoothIncrementsInTheCamerasAxes) {
  const FilterRun r = run(circle, Eigen::Vector3d(0.001, 0.002, 0.004), 900);
  double sum = 0;
  int n = 0;
  for (std::size_t i = 10; i < r.truth.size(); ++i) {
    const Eigen::Vector3d error =
        r.rotations[i].transpose() * ((r.smooth[i] - r.smooth[i - 1]) - (r.truth[i] - r.truth[i - 1]));
    const Eigen::Matrix3d C = r.published[i - 3].topLeftCorner<3, 3>();
    sum += error.dot(C.ldlt().solve(error));
    ++n;
    EXPECT_TRUE((r.published[i - 3].topRightCorner<3, 3>().isZero()));
  }
  const double nees = sum / n;
  std::printf("smooth increment's translation NEES %.2f (consistent: 3)\n", nees);
  EXPECT_GT(nees, 1.0);
  EXPECT_LT(nees, 6.0);
}

// A frame without a measured motion (a restart, a failure) starts the filter again: the tracked
// pose is published as it is, until three frames have given it an acceleration.
TEST(SmoothPosition, AFrameWithoutAMeasuredMotionStartsAgainAtTheTrackedPose) {
  SmoothPosition filter;
  core::Matrix6d relative = core::Matrix6d::Identity() * 1e-6;
  double t = 1000;
  for (int i = 0; i < 30; ++i, t += 1 / 30.0)
    smooth(filter, t, core::SE3::from_translation(Eigen::Vector3d(0.01 * i, 0, 0)), relative);
  const core::SE3 jump = core::SE3::from_translation(Eigen::Vector3d(5, 5, 5));
  const SmoothStep lost = smooth(filter, t, jump, std::nullopt);
  EXPECT_EQ(lost.pose.translation(), jump.translation());
  EXPECT_FALSE(lost.relative.has_value());
  const core::SE3 next = core::SE3::from_translation(Eigen::Vector3d(5.01, 5, 5));
  const SmoothStep first = smooth(filter, t + 1 / 30.0, next, relative);
  EXPECT_EQ(first.pose.translation(), next.translation()) << "the second frame: no acceleration yet";
  EXPECT_EQ(*first.relative, relative);
  const core::SE3 third = core::SE3::from_translation(Eigen::Vector3d(5.03, 5, 5));
  EXPECT_NE(smooth(filter, t + 2 / 30.0, third, relative).pose.translation(), third.translation()) << "filtered";
  // A stamp that does not advance is no motion either.
  const core::SE3 same = core::SE3::from_translation(Eigen::Vector3d(6, 5, 5));
  EXPECT_EQ(smooth(filter, t + 2 / 30.0, same, relative).pose.translation(), same.translation());
}

}  // namespace
}  // namespace cvo::odometry
