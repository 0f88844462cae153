#pragma once
// slam::SessionCorrection <-> cvo_lcm::map_correction_t (channel CVO_MAP_CORRECTION): one session's
// entry of the map, at the map's revision, with its newest loops to other sessions, each with the
// other keyframe's pose. Target cvo::lcm_map (it links the back end); what a tracker checks of a
// received one is map_check.hpp's and map_decision.hpp's, in the wire library.
#include <cstdint>
#include <optional>
#include <string>

#include "cvo_lcm/map_correction_t.hpp"
#include "libcvo/slam/mapper.hpp"

namespace cvo::lcm {

/// `epoch`: when the publishing back end started (map_t.epoch). At most MAX_LOOPS loops go (the
/// newest: correction.loops is newest first).
/// `acknowledged`: keyframes of the session below this id are stored with their local graphs
/// (map_correction_t.acknowledged).
cvo_lcm::map_correction_t to_message(const slam::SessionCorrection& correction, std::int64_t utime, std::int64_t epoch,
                                     std::int64_t acknowledged = 0);

/// Fails as map_check.hpp's correction_error() does.
std::optional<slam::SessionCorrection> from_message(const cvo_lcm::map_correction_t& message, std::string* error);

}  // namespace cvo::lcm
