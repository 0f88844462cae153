#include "libcvo/slam/trajectory_correction.hpp"

#include <gtest/gtest.h>

namespace cvo::slam {
namespace {

core::SE3 at_x(double x) { return core::SE3::from_translation({x, 0, 0}); }

TEST(TrajectoryCorrection, FramesTheBackEndLacksMoveWithTheirNeighbour) {
  const core::Trajectory odometry = {{0.0, at_x(0)}, {1.0, at_x(1)}, {2.0, at_x(2)}, {3.0, at_x(3)}, {4.0, at_x(4)}};
  // The back end has frames 1 and 3, shifted by +10 and +20 in y; it lacks 0, 2 and 4.
  const core::SE3 up10 = core::SE3::from_translation({0, 10, 0}), up20 = core::SE3::from_translation({0, 20, 0});
  const core::Trajectory optimised = {{1.0, up10 * at_x(1)}, {3.0, up20 * at_x(3)}};
  const core::Trajectory out = correct_trajectory(odometry, optimised);
  ASSERT_EQ(out.size(), 5u);
  const double expected_y[] = {10, 10, 10, 20, 20};  // frame 0 has no earlier one: it takes frame 1's
  for (std::size_t i = 0; i < out.size(); ++i) {
    EXPECT_EQ(out[i].timestamp, odometry[i].timestamp);
    EXPECT_NEAR(out[i].pose.translation().x(), static_cast<double>(i), 1e-12) << i;
    EXPECT_NEAR(out[i].pose.translation().y(), expected_y[i], 1e-12) << i;
  }
  // Nothing in common: the odometry as it is.
  const core::Trajectory same = correct_trajectory(odometry, {{7.5, up10}});
  EXPECT_NEAR(same[4].pose.translation().y(), 0.0, 1e-15);
}

}  // namespace
}  // namespace cvo::slam
