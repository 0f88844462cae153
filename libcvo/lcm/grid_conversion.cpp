#include "libcvo/lcm/grid_conversion.hpp"

#include <algorithm>
#include <cmath>

#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {
namespace {

bool known_cell(std::int8_t value) {
  return value == cvo_lcm::grid_t::CELL_UNKNOWN || value == cvo_lcm::grid_t::CELL_FREE ||
         value == cvo_lcm::grid_t::CELL_OCCUPIED;
}

// Why `m` is not a grid ("" when it is), and of which kind.
std::string grid_error(const cvo_lcm::grid_t& m, ContentFailure& kind) {
  kind = ContentFailure::kVersion;
  if (m.version != cvo_lcm::grid_t::SCHEMA_VERSION) return "schema version " + std::to_string(m.version);
  kind = ContentFailure::kNotFinite;
  if (!is_finite(m.map_T_grid)) return "map_T_grid is not finite";
  if (!std::isfinite(m.resolution) || !std::isfinite(m.origin[0]) || !std::isfinite(m.origin[1]) ||
      !std::isfinite(m.origin[2]))
    return "resolution or origin is not finite";
  kind = ContentFailure::kContent;
  if (m.frame != kGridFrame) return "frame '" + m.frame + "', not '" + kGridFrame + "'";
  if (m.up < cvo_lcm::grid_t::UP_MOUNT || m.up > cvo_lcm::grid_t::UP_FLOOR_PLANE)
    return "unknown up source " + std::to_string(m.up);
  if (m.revision < 0) return "negative revision " + std::to_string(m.revision);
  if (!(m.resolution > 0)) return "resolution " + std::to_string(m.resolution) + " is not positive";
  if (m.origin[2] != 0) return "origin yaw " + std::to_string(m.origin[2]) + " (a grid's cells are not turned)";
  if (m.width < 0 || m.height < 0) return "negative size " + std::to_string(m.width) + " x " + std::to_string(m.height);
  if (std::int64_t{m.width} * m.height != m.num_cells || m.cells.size() != static_cast<std::size_t>(m.num_cells))
    return std::to_string(m.num_cells) + " cells for " + std::to_string(m.width) + " x " + std::to_string(m.height);
  if (const auto bad = std::find_if_not(m.cells.begin(), m.cells.end(), known_cell); bad != m.cells.end())
    return "cell " + std::to_string(bad - m.cells.begin()) + " is " + std::to_string(*bad) + " (not -1, 0 or 100)";
  std::string why;
  if (!from_message(m.map_T_grid, &why)) return "map_T_grid: " + why;
  return {};
}

}  // namespace

cvo_lcm::grid_t to_message(const mapping::MapGrid& grid, std::int64_t utime, std::int64_t epoch) {
  cvo_lcm::grid_t m{};
  m.version = cvo_lcm::grid_t::SCHEMA_VERSION;
  m.utime = utime;
  m.revision = static_cast<std::int64_t>(grid.revision);
  m.epoch = epoch;
  m.map_T_grid = to_message(grid.frame.map_T_grid);
  m.up = static_cast<std::int8_t>(grid.frame.up);
  m.resolution = grid.grid.resolution;
  m.origin[0] = grid.grid.origin.x();
  m.origin[1] = grid.grid.origin.y();
  m.origin[2] = 0;
  m.width = grid.grid.width;
  m.height = grid.grid.height;
  m.cells = grid.grid.cells;
  m.num_cells = static_cast<std::int32_t>(m.cells.size());
  m.frame = kGridFrame;
  return m;
}

std::optional<mapping::MapGrid> from_message(const cvo_lcm::grid_t& m, std::string* error, ContentFailure* failure) {
  ContentFailure kind = ContentFailure::kContent;
  if (std::string why = grid_error(m, kind); !why.empty()) {
    if (error != nullptr) *error = "cvo_lcm.grid_t: " + why;
    if (failure != nullptr) *failure = kind;
    return std::nullopt;
  }
  mapping::MapGrid grid;
  grid.revision = static_cast<std::uint64_t>(m.revision);
  grid.frame.map_T_grid = *from_message(m.map_T_grid, nullptr);  // grid_error checked it
  grid.frame.up = static_cast<mapping::UpSource>(m.up);
  grid.grid.resolution = m.resolution;
  grid.grid.origin = {m.origin[0], m.origin[1]};
  grid.grid.width = m.width;
  grid.grid.height = m.height;
  grid.grid.cells = m.cells;
  return grid;
}

}  // namespace cvo::lcm
