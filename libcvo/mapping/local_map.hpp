#pragma once
// A keyframe's local map, made once from its depth and colour, in its own frame (no pose enters
// it, so a loop closure that moves the keyframe moves its local map and never re-reads its depth):
//
//   cloud      camera frame: the mean point and colour of every voxel (voxel_size) holding depth
//              measured within max_range, every pixel_stride-th pixel back-projected through the
//              undistorted pixel rays. Millimetres and 8-bit colour: 10 bytes a voxel.
//   footprint  the keyframe's levelled frame (origin the camera centre, z up, x the optical axis
//              made horizontal) on a lattice of half-cells, so that a footprint placed at any yaw
//              samples every grid cell it covers; of every half-cell column:
//                its surface voxels  the heights of the half-cell voxels holding cloud points;
//                its lowest ray      the lowest height at which a ray from the camera to a
//                                    surface voxel crossed it before reaching that voxel's cell.
//              Which heights are obstacles and which are floor is decided where the footprint is
//              placed: the floor's height is known only there.
//
// Both are bounded: the cloud by the image (pixels / stride²) and by max_range, the footprint by
// max_range² / half-cell².
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/rgbd_frame.hpp"

namespace cvo::mapping {

struct CloudPoint {
  std::int16_t x = 0, y = 0, z = 0;  // mm
  std::uint8_t r = 0, g = 0, b = 0;

  [[nodiscard]] Eigen::Vector3f position() const { return Eigen::Vector3f(x, y, z) * 1e-3f; }
};

/// A half-cell column of the footprint: what lies in it.
struct FootprintColumn {
  static constexpr std::int16_t kNoRay = INT16_MAX;
  std::int16_t i = 0, j = 0;        // half-cell indices along x, y of the levelled frame
  std::int16_t ray_k_min = kNoRay;  // lowest half-cell height a ray crossed it at
  std::uint16_t surfaces = 0;       // its surface voxels (their heights in Footprint::surface_k)
};

struct Footprint {
  double half_cell = 0.025;  // m
  Eigen::Matrix3d level_R_camera = Eigen::Matrix3d::Identity();
  std::vector<FootprintColumn> columns;  // by i, then j
  std::vector<std::int16_t> surface_k;   // each column's surface voxel heights, ascending, columns in order
  std::int16_t i_min = 0, i_max = -1, j_min = 0, j_max = -1;  // bounds of the columns (empty: i_max < i_min)

  [[nodiscard]] std::size_t bytes() const {
    return sizeof(Footprint) + columns.capacity() * sizeof(FootprintColumn) +
           surface_k.capacity() * sizeof(std::int16_t);
  }
};

/// The voxel cloud of `frame` (see the header); `pixel_rays` are core::undistorted_pixel_rays of
/// its intrinsics. Pixels without depth, beyond max_range or out of the int16 millimetre range
/// are skipped.
std::vector<CloudPoint> make_local_cloud(const core::RgbdFrame& frame, const std::vector<float>& pixel_rays,
                                         const core::MappingParameters& parameters);

/// The footprint of a local cloud levelled by `level_R_camera` (a rotation taking the camera's up
/// to +z).
Footprint make_footprint(const std::vector<CloudPoint>& cloud, const Eigen::Matrix3d& level_R_camera,
                         const core::MappingParameters& parameters);

}  // namespace cvo::mapping
