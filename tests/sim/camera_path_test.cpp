#include "libcvo/sim/camera_path.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>

#include <gtest/gtest.h>

#include "libcvo/sim/scene.hpp"

namespace cvo::sim {
namespace {

TEST(ScenePath, NamesRoundTrip) {
  for (const auto& name : path_names()) {
    const auto kind = parse_path_kind(name);
    ASSERT_TRUE(kind) << name;
    EXPECT_EQ(path_name(*kind), name);
  }
  EXPECT_FALSE(parse_path_kind("spiral"));
}

TEST(ScenePath, LookAtPointsTheOpticalAxisAndKeepsImageXLevel) {
  const core::SE3 pose = look_at({1, 2, 1}, {1, 4, 1});
  EXPECT_TRUE((pose.rotation_matrix().col(2)).isApprox(Eigen::Vector3d::UnitY()));   // z forward
  EXPECT_TRUE((pose.rotation_matrix().col(0)).isApprox(Eigen::Vector3d::UnitX()));   // x right
  EXPECT_TRUE((pose.rotation_matrix().col(1)).isApprox(-Eigen::Vector3d::UnitZ()));  // y down
  EXPECT_TRUE(pose.translation().isApprox(Eigen::Vector3d(1, 2, 1)));
}

// Every path, sampled at 30 Hz over a full period: inside the room, >= 0.5 m from every surface
// of every scene, hand-held speeds, and back at the start after one period. rpy turns in place,
// faster than the others (as TUM's fr1/rpy does).
TEST(ScenePath, StaysClearOfSurfacesAtHandHeldSpeeds) {
  const Scene room = make_scene(SceneKind::textured_room, 0);
  const Scene wall = make_scene(SceneKind::textured_wall, 0);
  for (const auto& name : path_names()) {
    const PathKind kind = *parse_path_kind(name);
    const auto frames = static_cast<std::size_t>(path_period(kind) * 30.0) + 1;
    const core::Trajectory poses = sample_path(kind, frames);
    double clearance = 1e9, max_speed = 0, max_rate_deg = 0;
    for (std::size_t i = 0; i < poses.size(); ++i) {
      const Eigen::Vector3d& p = poses[i].pose.translation();
      EXPECT_TRUE(room_bounds().contains(p)) << name << " frame " << i;
      clearance = std::min({clearance, distance_to_surface(room, p), distance_to_surface(wall, p)});
      if (i == 0) continue;
      const double dt = poses[i].timestamp - poses[i - 1].timestamp;
      const core::SE3 step = poses[i - 1].pose.inverse() * poses[i].pose;
      max_speed = std::max(max_speed, step.translation().norm() / dt);
      max_rate_deg = std::max(max_rate_deg, step.angle() / dt * 180.0 / std::numbers::pi);
    }
    EXPECT_GE(clearance, 0.5) << name;
    EXPECT_LE(max_speed, 0.5) << name;
    const bool turns_in_place = kind == PathKind::rpy || kind == PathKind::fast_rpy;
    EXPECT_LE(max_rate_deg, kind == PathKind::fast_rpy ? 250.0 : turns_in_place ? 90.0 : 60.0) << name;
    if (turns_in_place) {
      EXPECT_GT(max_rate_deg, 60.0) << name << " turns slowly";
      EXPECT_LT(max_speed, kind == PathKind::fast_rpy ? 0.3 : 0.1) << name << " does not stay in place";
    } else {
      EXPECT_GT(max_speed, 0.1) << name << " hardly moves";
    }
    const core::SE3 back = path_pose(kind, 0).inverse() * path_pose(kind, path_period(kind));
    EXPECT_LT(back.translation().norm(), 1e-9) << name;
    EXPECT_LT(back.angle(), 1e-9) << name;
  }
}

// Peak angular rate as camera_path.hpp measures fr1/rpy's: the angle between the poses 0.05 s
// before and after, over 0.1 s, at every millisecond of one period.
double peak_rate_deg_s(PathKind kind) {
  double peak = 0;
  for (double t = 0; t < path_period(kind); t += 1e-3) {
    const core::SE3 step = path_pose(kind, t - 0.05).inverse() * path_pose(kind, t + 0.05);
    peak = std::max(peak, step.angle() / 0.1 * 180.0 / std::numbers::pi);
  }
  return peak;
}

TEST(ScenePath, FastRpyTurnsAtOneAndAHalfTimesFr1RpysPeakRate) {
  EXPECT_DOUBLE_EQ(kFr1RpyPeakRateDegS, 158.1);
  const double fast = peak_rate_deg_s(PathKind::fast_rpy), slow = peak_rate_deg_s(PathKind::rpy);
  std::cout << "peak rate (0.1 s window): rpy " << slow << " deg/s, fast_rpy " << fast << " deg/s\n";
  EXPECT_NEAR(fast, 1.5 * kFr1RpyPeakRateDegS, 0.01 * 1.5 * kFr1RpyPeakRateDegS);
  // The same turns, only faster.
  for (const double t : {0.3, 1.7, 3.1}) {
    const core::SE3 e = path_pose(PathKind::rpy, kFastRpyTimeScale * t).inverse() * path_pose(PathKind::fast_rpy, t);
    EXPECT_LT(e.angle() + e.translation().norm(), 1e-12) << t;
  }
}

TEST(ScenePath, OrbitPansAFullTurn) {
  // The optical axis's heading sweeps all of [0, 360) degrees: the loop sees every wall.
  std::vector<bool> seen(36, false);
  for (const auto& [t, pose] : sample_path(PathKind::orbit, 360)) {
    const Eigen::Vector3d z = pose.rotation_matrix().col(2);
    const double heading = std::atan2(z.y(), z.x()) * 180.0 / std::numbers::pi + 180.0;
    seen[static_cast<std::size_t>(heading / 10.0) % 36] = true;
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), true), 36);
}

TEST(ScenePath, StampsAreMicrosecondRounded30Hz) {
  const auto poses = sample_path(PathKind::sweep, 4, 1000.0, 30.0);
  ASSERT_EQ(poses.size(), 4u);
  EXPECT_DOUBLE_EQ(poses[0].timestamp, 1000.0);
  EXPECT_DOUBLE_EQ(poses[1].timestamp, 1000.033333);
  EXPECT_DOUBLE_EQ(poses[2].timestamp, 1000.066667);
}

}  // namespace
}  // namespace cvo::sim
