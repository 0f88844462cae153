#include "libcvo/mapping/occupancy.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cvo::mapping {
namespace {

double logit(double p) { return std::log(p / (1 - p)); }

// floor() without the library call the baseline x86-64 target makes of std::floor (no SSE4.1
// roundsd): placing a footprint is two of these per column.
std::int64_t floor_index(double v) {
  const auto i = static_cast<std::int64_t>(v);
  return i - (v < static_cast<double>(i));
}

}  // namespace

FootprintPlacement place_footprint(const core::SE3& grid_T_camera, const Eigen::Matrix3d& level_R_camera) {
  const Eigen::Matrix3d grid_R_level = grid_T_camera.rotation_matrix() * level_R_camera.transpose();
  return {std::atan2(grid_R_level(1, 0), grid_R_level(0, 0)), grid_T_camera.translation()};
}

Cell OccupancyGrid::at_point(double x, double y) const {
  const auto column = static_cast<long>(std::floor((x - origin.x()) / resolution));
  const auto row = static_cast<long>(std::floor((y - origin.y()) / resolution));
  if (column < 0 || row < 0 || column >= width || row >= height) return Cell::unknown;
  return at(static_cast<int>(column), static_cast<int>(row));
}

OccupancyCounts::OccupancyCounts(const core::MappingParameters& parameters) : parameters_(parameters) {}

void OccupancyCounts::clear() {
  counts_.clear();
  i0_ = j0_ = width_ = height_ = 0;
}

void OccupancyCounts::cover(std::int64_t i_min, std::int64_t j_min, std::int64_t i_max, std::int64_t j_max) {
  if (width_ > 0 && i_min >= i0_ && j_min >= j0_ && i_max < i0_ + width_ && j_max < j0_ + height_) return;
  // Grow by half again in every direction it must, so that a map that keeps growing is copied
  // a logarithmic number of times.
  constexpr std::int64_t kMargin = 64;
  std::int64_t ni0 = i_min - kMargin, nj0 = j_min - kMargin, ni1 = i_max + kMargin, nj1 = j_max + kMargin;
  if (width_ > 0) {
    ni0 = std::min(ni0, i0_), nj0 = std::min(nj0, j0_);
    ni1 = std::max(ni1, i0_ + width_ - 1), nj1 = std::max(nj1, j0_ + height_ - 1);
    const std::int64_t grow_i = width_ / 2, grow_j = height_ / 2;
    if (i_min < i0_) ni0 -= grow_i;
    if (i_max >= i0_ + width_) ni1 += grow_i;
    if (j_min < j0_) nj0 -= grow_j;
    if (j_max >= j0_ + height_) nj1 += grow_j;
  }
  const std::int64_t nw = ni1 - ni0 + 1, nh = nj1 - nj0 + 1;
  std::vector<Count> grown(static_cast<std::size_t>(nw * nh));
  for (std::int64_t j = 0; j < height_; ++j)
    std::copy_n(counts_.begin() + j * width_, width_, grown.begin() + ((j + j0_ - nj0) * nw + (i0_ - ni0)));
  counts_ = std::move(grown);
  i0_ = ni0, j0_ = nj0, width_ = nw, height_ = nh;
}

void OccupancyCounts::apply(const Footprint& footprint, const FootprintPlacement& placement, int sign) {
  if (footprint.i_max < footprint.i_min) return;  // an empty footprint
  const double h = footprint.half_cell, inverse_cell = 1.0 / parameters_.cell_size;
  const double c = std::cos(placement.yaw), s = std::sin(placement.yaw);
  const Eigen::Vector3d& t = placement.translation;
  const auto cell_of = [&](std::int16_t i, std::int16_t j) {
    const double x = (i + 0.5) * h, y = (j + 0.5) * h;
    return std::pair<std::int64_t, std::int64_t>{floor_index((c * x - s * y + t.x()) * inverse_cell),
                                                 floor_index((s * x + c * y + t.y()) * inverse_cell)};
  };
  std::int64_t lo_i = std::numeric_limits<std::int64_t>::max(), lo_j = lo_i;
  std::int64_t hi_i = std::numeric_limits<std::int64_t>::min(), hi_j = hi_i;
  for (const auto i : {footprint.i_min, footprint.i_max})
    for (const auto j : {footprint.j_min, footprint.j_max}) {
      const auto [ci, cj] = cell_of(i, j);
      lo_i = std::min(lo_i, ci - 1), lo_j = std::min(lo_j, cj - 1);
      hi_i = std::max(hi_i, ci + 1), hi_j = std::max(hi_j, cj + 1);
    }
  cover(lo_i, lo_j, hi_i, hi_j);
  if (++serial_ == 0) {  // the stamps wrapped: none may look like this placement's
    for (auto& count : counts_) count.stamp = 0;
    serial_ = 1;
  }
  changed_last_ = 0;

  // A voxel of height k lies at (k + 1/2) h + t.z above the floor: obstacle heights are [k_low, k_high].
  const auto k_low = static_cast<std::int64_t>(std::ceil((parameters_.obstacle_min_height - t.z()) / h - 0.5));
  const auto k_high = static_cast<std::int64_t>(std::floor((parameters_.obstacle_max_height - t.z()) / h - 0.5));
  std::size_t next = 0;
  for (const auto& column : footprint.columns) {
    const std::int16_t* k = footprint.surface_k.data() + next;
    next += column.surfaces;
    const std::int16_t* k_end = footprint.surface_k.data() + next;
    const std::int16_t* above_floor = std::lower_bound(k, k_end, k_low);
    const bool hit = above_floor != k_end && *above_floor <= k_high;
    const bool floor = above_floor != k;  // a surface below obstacle_min_height: the floor, seen
    const bool crossed = column.ray_k_min <= k_high;
    if (!hit && !floor && !crossed) continue;
    const auto [i, j] = cell_of(column.i, column.j);
    auto& count = counts_[static_cast<std::size_t>((j - j0_) * width_ + (i - i0_))];
    if (count.stamp != serial_) {  // this placement's first word on the cell
      count.stamp = serial_, count.hit = hit;
      (hit ? count.hits : count.misses) += sign;
      ++changed_last_;
    } else if (hit && !count.hit) {  // a hit outweighs the misses of the same placement
      count.hit = 1;
      count.misses -= sign, count.hits += sign;
    }
  }
}

OccupancyGrid OccupancyCounts::grid() const {
  OccupancyGrid grid;
  grid.resolution = parameters_.cell_size;
  std::int64_t lo_i = width_, lo_j = height_, hi_i = -1, hi_j = -1;
  for (std::int64_t j = 0; j < height_; ++j)
    for (std::int64_t i = 0; i < width_; ++i) {
      const auto& count = counts_[static_cast<std::size_t>(j * width_ + i)];
      if (count.hits == 0 && count.misses == 0) continue;
      lo_i = std::min(lo_i, i), lo_j = std::min(lo_j, j), hi_i = std::max(hi_i, i), hi_j = std::max(hi_j, j);
    }
  if (hi_i < 0) return grid;
  grid.width = static_cast<int>(hi_i - lo_i + 1);
  grid.height = static_cast<int>(hi_j - lo_j + 1);
  grid.origin =
      Eigen::Vector2d(static_cast<double>(i0_ + lo_i), static_cast<double>(j0_ + lo_j)) * parameters_.cell_size;
  grid.cells.resize(static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height));
  const double l_hit = logit(parameters_.hit_probability), l_miss = logit(parameters_.miss_probability);
  for (std::int64_t j = lo_j; j <= hi_j; ++j)
    for (std::int64_t i = lo_i; i <= hi_i; ++i) {
      const auto& count = counts_[static_cast<std::size_t>(j * width_ + i)];
      const double log_odds = count.hits * l_hit + count.misses * l_miss;
      const Cell cell = (count.hits == 0 && count.misses == 0) || log_odds == 0 ? Cell::unknown
                        : log_odds > 0                                          ? Cell::occupied
                                                                                : Cell::free;
      grid.cells[static_cast<std::size_t>((j - lo_j) * grid.width + (i - lo_i))] = static_cast<std::int8_t>(cell);
    }
  return grid;
}

}  // namespace cvo::mapping
