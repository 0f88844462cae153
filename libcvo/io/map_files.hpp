#pragma once
// The map in the formats people's tools read, each written through the library made for it:
//   grid.pgm + grid.yaml  as Nav2's map_server loads them (mode trinary: occupied 0, free 254,
//                         unknown 205; negate 0; occupied_thresh 0.65 and free_thresh 0.196, so
//                         that 205 reads back unknown, as ROS's map_saver writes them), origin the
//                         grid's lower-left corner in the grid frame, plus map_T_grid
//                         [x, y, z, qx, qy, qz, qw] (the grid frame in the map frame) and up (which
//                         way up came from). PGM through OpenCV's imgcodecs, YAML through yaml-cpp.
//   cloud.ply             coloured points in the map frame, binary, through Open3D.
//   octomap.bt            the OctoMap octree (grid frame), through OctoMap.
//   --plot PNG            the grid with the keyframe trajectory on it (OpenCV).
// Each file is written under a temporary name and renamed, so that a reader never sees half a map.
#include <filesystem>
#include <vector>

#include <Eigen/Core>

#include "libcvo/mapping/mapping.hpp"

namespace cvo::io {

struct MapFiles {
  std::filesystem::path grid_pgm, grid_yaml, cloud_ply, octomap_bt;
};

/// map_server's trinary thresholds, as grid.yaml states them.
inline constexpr double kOccupiedThreshold = 0.65, kFreeThreshold = 0.196;

/// Writes the four files into `dir` (created if needed). Throws io::InputError naming the file
/// that cannot be written, or `dir` when the mapping has no grid yet (no keyframe said which way
/// is up).
MapFiles write_map_files(const std::filesystem::path& dir, const mapping::Mapping& mapping);

/// The grid (free white, occupied black, unknown grey) with `trajectory` (map-frame camera
/// centres, in order) drawn on it, its start marked; at least 800 px on its longer side.
void write_map_plot(const std::filesystem::path& png, const mapping::MapGrid& grid,
                    const std::vector<Eigen::Vector3d>& trajectory);

}  // namespace cvo::io
