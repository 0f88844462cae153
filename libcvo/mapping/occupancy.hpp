#pragma once
// The occupancy grid as the sum of its keyframes' footprints, each placed at its keyframe's pose.
//
// A footprint is placed in the grid frame (z up, z = 0 on the floor) by the yaw and position of its
// levelled frame: grid_T_level = grid_T_camera · level_R_camera⁻¹, whose remaining tilt (what a
// loop closure corrects beyond yaw, a degree or two) is dropped. A placed footprint says, of each
// grid cell it covers, one thing:
//   hit   a surface voxel of it lies between obstacle_min_height and obstacle_max_height;
//   miss  otherwise, when a surface voxel below obstacle_min_height (floor) lies in it, or a ray
//         crossed it no higher than obstacle_max_height (the robot's body would pass there).
// Every cell counts its hits and misses over keyframes, and is, as in OctoMap, occupied when its
// log-odds hits·logit(hit_probability) + misses·logit(miss_probability) is positive, free when it
// is negative, unknown when nothing was seen there. Counts are integers and a sum does not depend
// on its order, so removing a placement and adding another is exact: re-placing the keyframes a
// loop closure moved gives the grid that placing every keyframe anew gives, and touches only the
// cells of those keyframes. A cell seen free by more keyframes than its hits outweigh (a person who
// walked by, a box taken away) is free; a wall, hit by every keyframe that sees it and crossed by
// none of their rays, stays.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/mapping/local_map.hpp"

namespace cvo::mapping {

struct FootprintPlacement {
  double yaw = 0;                                         // of the levelled frame's x about the grid's z
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();  // the camera centre in the grid frame

  bool operator==(const FootprintPlacement&) const = default;
};

FootprintPlacement place_footprint(const core::SE3& grid_T_camera, const Eigen::Matrix3d& level_R_camera);

enum class Cell : std::int8_t { unknown = -1, free = 0, occupied = 100 };  // nav_msgs/OccupancyGrid's values

/// A trinary occupancy grid in the grid frame.
struct OccupancyGrid {
  double resolution = 0.05;                          // m per cell
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  // grid-frame x, y of cell (0, 0)'s outer corner
  int width = 0, height = 0;                         // cells along x, along y
  std::vector<std::int8_t> cells;                    // row-major, row 0 at the lowest y: Cell values

  [[nodiscard]] Cell at(int column, int row) const {
    return static_cast<Cell>(
        cells[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) + static_cast<std::size_t>(column)]);
  }
  /// The cell holding grid-frame (x, y); unknown outside the grid.
  [[nodiscard]] Cell at_point(double x, double y) const;
  bool operator==(const OccupancyGrid&) const = default;
};

class OccupancyCounts {
 public:
  explicit OccupancyCounts(const core::MappingParameters& parameters);

  void add(const Footprint& footprint, const FootprintPlacement& placement) { apply(footprint, placement, +1); }
  void remove(const Footprint& footprint, const FootprintPlacement& placement) { apply(footprint, placement, -1); }
  void clear();

  /// The grid over every cell that holds a count (empty when none does).
  [[nodiscard]] OccupancyGrid grid() const;
  /// Cells the last add() or remove() changed.
  [[nodiscard]] std::size_t cells_changed_last() const { return changed_last_; }
  [[nodiscard]] std::size_t bytes() const { return counts_.capacity() * sizeof(Count); }

 private:
  struct Count {
    std::int32_t hits = 0, misses = 0;
    std::uint32_t stamp = 0;  // the placement that last marked it, so that one placement counts once
    std::uint8_t hit = 0;     // whether that placement marked it a hit
  };
  void apply(const Footprint& footprint, const FootprintPlacement& placement, int sign);
  void cover(std::int64_t i_min, std::int64_t j_min, std::int64_t i_max, std::int64_t j_max);

  core::MappingParameters parameters_;
  std::vector<Count> counts_;
  std::int64_t i0_ = 0, j0_ = 0, width_ = 0, height_ = 0;  // counts_ covers cells [i0, i0 + width) x [j0, ...)
  std::uint32_t serial_ = 0;
  std::size_t changed_last_ = 0;
};

}  // namespace cvo::mapping
