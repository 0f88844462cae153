#include "libcvo/slam/trajectory_correction.hpp"

#include <optional>

namespace cvo::slam {

core::Trajectory correct_trajectory(const core::Trajectory& odometry, const core::Trajectory& optimised) {
  // Pass 1: the back end's pose where it has one (a merge of the two sorted lists).
  std::vector<std::optional<core::SE3>> slam(odometry.size());
  std::size_t j = 0;
  for (std::size_t i = 0; i < odometry.size(); ++i) {
    while (j < optimised.size() && optimised[j].timestamp < odometry[i].timestamp) ++j;
    if (j < optimised.size() && optimised[j].timestamp == odometry[i].timestamp) slam[i] = optimised[j].pose;
  }
  // Pass 2: the others move with the nearest earlier known frame (or the first known one).
  std::optional<core::SE3> correction;  // T_world_odometry of the latest known frame
  for (std::size_t i = 0; i < odometry.size() && !correction; ++i)
    if (slam[i]) correction = *slam[i] * odometry[i].pose.inverse();
  core::Trajectory out;
  out.reserve(odometry.size());
  for (std::size_t i = 0; i < odometry.size(); ++i) {
    if (slam[i]) correction = *slam[i] * odometry[i].pose.inverse();
    out.push_back({odometry[i].timestamp, slam[i] ? *slam[i] : correction.value_or(core::SE3()) * odometry[i].pose});
  }
  return out;
}

}  // namespace cvo::slam
