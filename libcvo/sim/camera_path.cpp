#include "libcvo/sim/camera_path.hpp"

#include <array>
#include <cmath>
#include <numbers>

#include "libcvo/core/units.hpp"

namespace cvo::sim {
namespace {

constexpr double kPi = std::numbers::pi;

struct KindName {
  PathKind kind;
  std::string_view name;
};
constexpr std::array kKindNames{
    KindName{PathKind::orbit, "orbit"}, KindName{PathKind::sweep, "sweep"},       KindName{PathKind::wall, "wall"},
    KindName{PathKind::rpy, "rpy"},     KindName{PathKind::fast_rpy, "fast_rpy"},
};

// Unit viewing direction from yaw (about world z, from +x) and pitch (up positive).
Eigen::Vector3d direction(double yaw, double pitch) {
  return {std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), std::sin(pitch)};
}

core::SE3 orbit(double seconds) {
  const double a = 2 * kPi * seconds / path_period(PathKind::orbit);
  const Eigen::Vector3d eye(0.5 * std::cos(a), 0.5 * std::sin(a), 1.3 + 0.1 * std::sin(2 * a));
  const double pitch = -0.4 + 0.1 * std::sin(3 * a);
  return look_at(eye, eye + direction(a, pitch), 0.06 * std::sin(2 * a));
}

core::SE3 sweep(double seconds) {
  const double s = 0.5 - 0.5 * std::cos(2 * kPi * seconds / path_period(PathKind::sweep));  // 0 -> 1 -> 0
  const Eigen::Vector3d start(-0.8, -1.2, 1.2), end(0.8, -0.8, 1.45);
  const Eigen::Vector3d eye = start + s * (end - start);
  const double yaw = core::radians(110.0 - 40.0 * s);
  const double pitch = -0.25 + 0.1 * s;
  return look_at(eye, eye + direction(yaw, pitch), 0.04 * std::sin(kPi * s));
}

core::SE3 wall(double seconds) {
  const double a = 2 * kPi * seconds / path_period(PathKind::wall);
  const Eigen::Vector3d eye(0.35 * std::sin(a), 0.5 + 0.2 * std::sin(2 * a), 1.3 + 0.12 * std::sin(3 * a + 0.5));
  const Eigen::Vector3d target(0.3 * std::sin(a + 1.0), 2.5, 1.3 + 0.25 * std::cos(2 * a));
  return look_at(eye, target, 0.09 * std::sin(a));
}

core::SE3 rpy(double seconds) {
  const double a = 2 * kPi * seconds / path_period(PathKind::rpy);
  const Eigen::Vector3d eye(0.02 * std::sin(2 * a), -0.8 + 0.02 * std::sin(3 * a), 1.3 + 0.02 * std::cos(a));
  const double yaw = core::radians(90.0 + 20.0 * std::sin(5 * a));
  const double pitch = core::radians(-15.0 + 12.0 * std::sin(7 * a + 0.3));
  return look_at(eye, eye + direction(yaw, pitch), core::radians(15.0) * std::sin(6 * a + 0.7));
}

}  // namespace

std::string_view path_name(PathKind kind) {
  for (const auto& k : kKindNames)
    if (k.kind == kind) return k.name;
  return "unknown";
}

std::optional<PathKind> parse_path_kind(std::string_view name) {
  for (const auto& k : kKindNames)
    if (k.name == name) return k.kind;
  return std::nullopt;
}

std::vector<std::string> path_names() {
  std::vector<std::string> names;
  for (const auto& k : kKindNames) names.emplace_back(k.name);
  return names;
}

double path_period(PathKind kind) {
  switch (kind) {
    case PathKind::wall: return 10.0;
    case PathKind::fast_rpy: return 12.0 / kFastRpyTimeScale;
    case PathKind::orbit:
    case PathKind::sweep:
    case PathKind::rpy: break;
  }
  return 12.0;
}

core::SE3 look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, double roll) {
  // Optical frame: z forward, x right, y down. right = forward x up keeps x horizontal.
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d r;
  r << x, y, z;
  return core::SE3(r, eye) * core::SE3::from_rotation_vector(Eigen::Vector3d(0, 0, roll));
}

core::SE3 path_pose(PathKind kind, double seconds) {
  switch (kind) {
    case PathKind::orbit: return orbit(seconds);
    case PathKind::sweep: return sweep(seconds);
    case PathKind::wall: return wall(seconds);
    case PathKind::rpy: return rpy(seconds);
    case PathKind::fast_rpy: return rpy(kFastRpyTimeScale * seconds);
  }
  return {};
}

core::Trajectory sample_path(PathKind kind, std::size_t frames, double start_time, double rate_hz) {
  core::Trajectory trajectory;
  trajectory.reserve(frames);
  for (std::size_t i = 0; i < frames; ++i) {
    const double stamp = std::round((start_time + static_cast<double>(i) / rate_hz) * 1e6) / 1e6;
    trajectory.push_back({stamp, path_pose(kind, stamp - start_time)});
  }
  return trajectory;
}

}  // namespace cvo::sim
