#pragma once
// What the mapping tests share: the rendered room (libcvo/sim) emptied of its furniture, with or
// without one box, seen by keyframes from a camera 1 m above the floor, and the slam::Map that
// places them at their exact poses. The map frame is the first keyframe's camera frame.
#include <vector>

#include <Eigen/Geometry>

#include "libcvo/core/se3.hpp"
#include "libcvo/mapping/mapping.hpp"
#include "libcvo/sim/camera_path.hpp"
#include "libcvo/sim/render.hpp"
#include "libcvo/sim/scene.hpp"
#include "libcvo/slam/mapper.hpp"
#include "tests/support/map_session.hpp"

namespace cvo::mapping::testing {

inline constexpr double kCameraHeight = 1.0;
// The box: 0.4 m on a side, 0.5 m tall, on the floor at (1.0, 1.2).
inline const Eigen::AlignedBox3d kBox(Eigen::Vector3d(0.8, 1.0, 0.0), Eigen::Vector3d(1.2, 1.4, 0.5));

/// The room's walls, floor and ceiling only; with `box`, kBox too (four sides and its top).
inline sim::Scene room(bool box) {
  sim::Scene scene = sim::make_scene(sim::SceneKind::textured_room, 3);
  scene.surfaces.resize(scene.objects.front().count);
  scene.objects.resize(1);
  if (!box) return scene;
  const Eigen::Vector3d lo = kBox.min(), hi = kBox.max(), size = hi - lo;
  const auto texture = scene.surfaces.front().texture;
  const std::size_t first = scene.surfaces.size();
  const auto quad = [&](Eigen::Vector3d origin, Eigen::Vector3d s, Eigen::Vector3d t, double ls, double lt) {
    scene.surfaces.push_back({sim::Quad{origin, s, t, ls, lt}, texture});
  };
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
  quad(lo, x, z, size.x(), size.z());                                       // y = lo
  quad(Eigen::Vector3d(lo.x(), hi.y(), 0), x, z, size.x(), size.z());       // y = hi
  quad(lo, y, z, size.y(), size.z());                                       // x = lo
  quad(Eigen::Vector3d(hi.x(), lo.y(), 0), y, z, size.y(), size.z());       // x = hi
  quad(Eigen::Vector3d(lo.x(), lo.y(), hi.z()), x, y, size.x(), size.y());  // top
  scene.objects.push_back({first, 5, Eigen::AlignedBox3d(lo, hi)});
  return scene;
}

/// A camera at (x, y, 1 m) looking along yaw (degrees from +x), pitched 15° down.
inline core::SE3 camera_at(double x, double y, double yaw_deg) {
  const double yaw = yaw_deg * M_PI / 180, pitch = 15 * M_PI / 180;
  const Eigen::Vector3d eye(x, y, kCameraHeight);
  const Eigen::Vector3d ahead(std::cos(yaw) * std::cos(pitch), std::sin(yaw) * std::cos(pitch), -std::sin(pitch));
  return sim::look_at(eye, eye + ahead);
}

// Half the synthetic preset's size: a map needs no more, and rendering costs a quarter.
inline core::Intrinsics camera() { return {262.5, 262.5, 159.5, 119.5, 320, 240, 5000.0}; }

/// The map: session 1, in the map frame, keyframe k at world_T_map⁻¹ · world_T_camera[k].
inline slam::Map map_of(const std::vector<core::SE3>& world_T_camera, std::uint64_t revision = 1) {
  slam::Map map;
  map.revision = revision;
  map.sessions.push_back(test::map_session(1, true, 1, world_T_camera.size(), 0, core::SE3()));
  const core::SE3 map_T_world = world_T_camera.front().inverse();
  for (std::size_t k = 0; k < world_T_camera.size(); ++k)
    map.keyframes.push_back({1, static_cast<std::int64_t>(k), static_cast<double>(k), map_T_world * world_T_camera[k]});
  return map;
}

/// The camera's mount on a base under it: 1 m up, pitched as camera_at's (a base with x along the
/// camera's heading).
inline core::PoseParameter mount() {
  const core::SE3 base_T_camera = camera_at(0, 0, 0);
  const auto& q = base_T_camera.rotation();
  const auto& t = base_T_camera.translation();
  return {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
}

}  // namespace cvo::mapping::testing
