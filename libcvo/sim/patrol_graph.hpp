#pragma once
// A simulated patrol as a pose graph: a robot drives the same closed route (a rectangle of
// corridors, gently rolling in height) lap after lap. Each step adds a node and its odometry edge
// (the true relative pose with Gaussian noise); from the second lap on, every `loop_every`-th
// step also closes a loop to the same place on the first lap. Nodes start at dead reckoning (the
// odometry composed), the initial guess a robot has. Deterministic for a seed (random.hpp).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "libcvo/core/se3.hpp"
#include "libcvo/posegraph/pose_graph.hpp"

namespace cvo::sim {

struct PatrolOptions {
  std::size_t route_poses = 100;  // poses per lap
  std::size_t laps = 3;           // times the route is driven
  std::size_t loop_every = 10;    // a loop every this many steps from the second lap on
  double width_m = 20.0;          // the rectangle's sides
  double depth_m = 10.0;
  double translation_sigma = 0.01;  // odometry and loop noise per step (m, each axis)
  double rotation_sigma = 0.002;    // (rad, each axis)
  bool robust_loops = true;         // loops with the Cauchy kernel, as the SLAM back end's
  std::uint64_t seed = 1;
};

struct PatrolGraph {
  posegraph::PoseGraph graph;    // node ids 0..n-1 in driving order; edges in the order they arise
  std::vector<core::SE3> truth;  // the true pose of every node
  std::size_t loops = 0;
};

PatrolGraph patrol_graph(const PatrolOptions& options = {});

}  // namespace cvo::sim
