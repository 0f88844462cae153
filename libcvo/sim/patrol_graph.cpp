#include "libcvo/sim/patrol_graph.hpp"

#include <array>
#include <cmath>
#include <numbers>

#include "libcvo/sim/random.hpp"

namespace cvo::sim {
namespace {

// The true pose at arc fraction u in [0, 1) of the rectangle, heading along it.
core::SE3 route_pose(double u, const PatrolOptions& o) {
  const double perimeter = 2.0 * (o.width_m + o.depth_m);
  double s = u * perimeter;
  const std::array<double, 4> sides{o.width_m, o.depth_m, o.width_m, o.depth_m};
  const std::array<Eigen::Vector2d, 4> corners{Eigen::Vector2d(0, 0), Eigen::Vector2d(o.width_m, 0),
                                               Eigen::Vector2d(o.width_m, o.depth_m), Eigen::Vector2d(0, o.depth_m)};
  int side = 0;
  while (side < 3 && s > sides[side]) s -= sides[side++];
  const double yaw = side * std::numbers::pi / 2;
  const Eigen::Vector2d xy = corners[side] + s * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
  const double z = 0.3 * std::sin(2.0 * std::numbers::pi * u * 3.0);
  return core::SE3::from_translation({xy.x(), xy.y(), z}) * core::SE3::from_rotation_vector({0, 0, yaw});
}

core::SE3 noisy(const core::SE3& T, const PatrolOptions& o, std::uint64_t key) {
  core::Vector6d xi;
  for (int k = 0; k < 6; ++k)
    xi[k] =
        (k < 3 ? o.translation_sigma : o.rotation_sigma) * gaussian(hash(o.seed, key, static_cast<std::uint64_t>(k)));
  return T * core::SE3::exp(xi);
}

core::Matrix6d information(const PatrolOptions& o) {
  core::Vector6d diagonal;
  diagonal << Eigen::Vector3d::Constant(1.0 / (o.translation_sigma * o.translation_sigma)),
      Eigen::Vector3d::Constant(1.0 / (o.rotation_sigma * o.rotation_sigma));
  return diagonal.asDiagonal();
}

}  // namespace

PatrolGraph patrol_graph(const PatrolOptions& o) {
  PatrolGraph patrol;
  const std::size_t n = o.route_poses * o.laps;
  const core::Matrix6d omega = information(o);
  for (std::size_t s = 0; s < n; ++s)
    patrol.truth.push_back(route_pose(static_cast<double>(s % o.route_poses) / static_cast<double>(o.route_poses), o));
  patrol.graph.add_node(0, patrol.truth[0]);
  for (std::size_t s = 1; s < n; ++s) {
    const auto id = static_cast<posegraph::NodeId>(s);
    const core::SE3 odometry = noisy(patrol.truth[s - 1].inverse() * patrol.truth[s], o, 2 * s);
    patrol.graph.add_node(id, patrol.graph.node(id - 1).pose * odometry);
    patrol.graph.add_edge({id - 1, id, odometry, omega, false});
    if (s < o.route_poses || s % o.loop_every != 0) continue;
    const std::size_t first_visit = s % o.route_poses;
    const core::SE3 loop = noisy(patrol.truth[first_visit].inverse() * patrol.truth[s], o, 2 * s + 1);
    patrol.graph.add_edge({static_cast<posegraph::NodeId>(first_visit), id, loop, omega, o.robust_loops});
    ++patrol.loops;
  }
  return patrol;
}

}  // namespace cvo::sim
