#pragma once
// The map's coloured cloud: every placed keyframe's local cloud at its pose in the map frame,
// voxel-downsampled again (voxel_size) so that surfaces seen by many keyframes are not many times
// denser than the rest: each voxel's mean point and mean colour.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "libcvo/core/se3.hpp"
#include "libcvo/mapping/local_map.hpp"

namespace cvo::mapping {

struct ColouredPoint {
  Eigen::Vector3f position = Eigen::Vector3f::Zero();
  std::uint8_t r = 0, g = 0, b = 0;
};

struct PlacedCloud {
  const std::vector<CloudPoint>* cloud = nullptr;
  core::SE3 map_T_camera;
};

/// Sorted by voxel, so that the same placed clouds give the same points in the same order.
std::vector<ColouredPoint> assemble_cloud(const std::vector<PlacedCloud>& clouds, double voxel_size);

}  // namespace cvo::mapping
