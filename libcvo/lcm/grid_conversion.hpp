#pragma once
// mapping::MapGrid <-> cvo_lcm::grid_t (channel CVO_GRID): the occupancy grid, its frame and the
// map revision it shows. Target cvo::lcm_grid (it links libcvo/mapping): the back end publishes
// it; cvo-trackerd neither links nor reads it.
#include <cstdint>
#include <optional>
#include <string>

#include "cvo_lcm/grid_t.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/mapping/mapping.hpp"

namespace cvo::lcm {

/// The name of the frame the cells lie in (grid_t.frame): z up, z = 0 on the floor.
inline constexpr const char* kGridFrame = "grid";

/// `epoch`: the publishing back end's CVO_MAP epoch (map_t.epoch).
cvo_lcm::grid_t to_message(const mapping::MapGrid& grid, std::int64_t utime, std::int64_t epoch);

/// Fails (nullopt, *error; *failure, when given, the kind) on a grid that cannot be the grid it
/// says: another schema version or frame, an unknown up source, a negative revision or size,
/// num_cells other than width * height, a resolution that is not finite and positive, an origin
/// that is not finite or turned (yaw other than 0), a pose that is not a rigid transform, a cell
/// other than -1, 0 or 100. Another version is kVersion, non-finite numbers kNotFinite, the rest
/// kContent.
std::optional<mapping::MapGrid> from_message(const cvo_lcm::grid_t& message, std::string* error,
                                             ContentFailure* failure = nullptr);

}  // namespace cvo::lcm
