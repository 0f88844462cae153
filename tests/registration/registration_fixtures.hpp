#pragma once
// Shared helpers of the registration tests: rendered scenes at known poses, real frames.
#include <cmath>
#include <numbers>

#include "libcvo/core/camera.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/registration/point_cloud.hpp"
#include "libcvo/registration/point_selection.hpp"
#include "libcvo/sim/render.hpp"
#include "libcvo/sim/scene.hpp"

namespace cvo::registration::testing {

inline double deg(double rad) { return rad * 180.0 / std::numbers::pi; }
inline double rad(double deg) { return deg * std::numbers::pi / 180.0; }

/// A camera standing in the room at (x, y, 1.3 m), looking along +y, level.
inline core::SE3 camera_looking_north(double x = 0.0, double y = -1.0) {
  Eigen::Matrix3d R;
  R.col(0) = Eigen::Vector3d::UnitX();   // camera x: right
  R.col(1) = -Eigen::Vector3d::UnitZ();  // camera y: down
  R.col(2) = Eigen::Vector3d::UnitY();   // camera z: forward
  return {R, Eigen::Vector3d(x, y, 1.3)};
}

/// A camera motion M (in the first camera's frame) of `angle_deg` about `axis` and `translation`.
inline core::SE3 motion(const Eigen::Vector3d& axis, double angle_deg, const Eigen::Vector3d& translation) {
  return {Eigen::Quaterniond(Eigen::AngleAxisd(rad(angle_deg), axis.normalized())), translation};
}

struct RenderedPair {
  PointCloud first{8192}, second{8192};
};

/// Renders the scene from `pose` and from `pose * M` and selects points in both: aligning
/// (first, second) must give M, since second's points map into first's frame by M.
inline RenderedPair render_pair(sim::SceneKind kind, const core::SE3& pose, const core::SE3& M,
                                const core::SelectionParameters& selection = {}) {
  const auto scene = sim::make_scene(kind, 42);
  const auto K = *core::camera_preset("synthetic");
  PointSelector selector(K.width, K.height, selection);
  RenderedPair pair;
  selector.select(sim::render(scene, K, pose), pair.first);
  selector.select(sim::render(scene, K, pose * M), pair.second);
  return pair;
}

}  // namespace cvo::registration::testing
