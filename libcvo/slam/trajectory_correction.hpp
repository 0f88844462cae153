#pragma once
// The SLAM trajectory of every frame of a run, also of those the back end never saw.
//
// A frame the tracker could not register (no points, or both registrations failed) keeps its
// constant-velocity prediction and enters no local graph, so the back end has no pose for it.
// Such a frame gets the correction of the nearest earlier frame that has both poses:
//   P_slam(n) = P_slam(k) P_odometry(k)⁻¹ P_odometry(n),   k < n the latest frame in both,
// (the nearest later one when there is none earlier), i.e. it moves rigidly with its neighbour.
#include "libcvo/core/trajectory.hpp"

namespace cvo::slam {

/// `odometry`: the tracker's pose of every frame; `optimised`: the back end's poses of a subset of
/// them (the same timestamps, exactly). Both sorted by timestamp. Returns one pose per odometry
/// frame, in its order; `odometry` itself when `optimised` shares no timestamp with it.
core::Trajectory correct_trajectory(const core::Trajectory& odometry, const core::Trajectory& optimised);

}  // namespace cvo::slam
