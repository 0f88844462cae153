#pragma once
// Which way is up, and the grid frame (z up, z = 0 on the floor) that follows from it.
//
// In order of trust:
//   mount          mapping.base_T_camera, the camera's pose on a base whose z is up and whose
//                  origin is on the floor: a robot knows how its camera is mounted. The grid frame
//                  is the base frame at the map's first keyframe.
//   accelerometer  the specific force an accelerometer at rest measures points up; where the
//                  recording has one, each keyframe is levelled by its own reading, and the map's
//                  up is their mean carried into the map frame by the keyframes' poses.
//   floor plane    else the dominant horizontal plane each keyframe sees (the floor, a table top:
//                  either is level), found by RANSAC among planes within 60° of the image's up; the
//                  map's up is their mean in the map frame, and each keyframe is levelled by it.
// Without a mount the floor's height is not known: it is the lowest level that holds a share of
// the map's surfaces (floor_height), the floor where the map sees one.
#include <map>
#include <optional>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "libcvo/core/se3.hpp"
#include "libcvo/mapping/local_map.hpp"

namespace cvo::mapping {

enum class UpSource : std::int8_t { mount = 0, accelerometer = 1, floor_plane = 2 };
std::string_view up_source_name(UpSource source);  // "mount", "accelerometer", "floor plane"

/// The rotation level_R_camera taking `up_camera` (any length but zero) to +z, whose x is the
/// optical axis made horizontal (the camera's x when it looks straight up or down).
Eigen::Matrix3d level_rotation(const Eigen::Vector3d& up_camera);

/// The rotation of the grid frame in the map frame: z along `up_map`, x along the first
/// keyframe's optical axis made horizontal (`map_R_camera` its rotation).
Eigen::Matrix3d grid_rotation(const Eigen::Vector3d& up_map, const Eigen::Matrix3d& map_R_camera);

/// The unit normal, pointing to the camera's side, of the plane with most points of `cloud`
/// within `inlier_distance` among planes below the camera whose normal is within 60° of the image's
/// up (-y); nullopt when none holds a fifth of the points. Deterministic.
std::optional<Eigen::Vector3d> horizontal_plane_up(const std::vector<CloudPoint>& cloud, double inlier_distance);

/// Heights (any unit) counted in bins: the floor is the lowest bin at or below which lies 1 % of
/// every count, so that a few points of noise below the floor do not move it.
class HeightHistogram {
 public:
  void add(long bin, long count) { counts_[bin] += count, total_ += count; }
  [[nodiscard]] std::optional<long> floor_bin() const;

 private:
  std::map<long, long> counts_;
  long total_ = 0;
};

}  // namespace cvo::mapping
