#pragma once
// slam::Map <-> cvo_lcm::map_t (channel CVO_MAP): sessions with their placement and correction,
// keyframes by (session, id), loops between sessions. Target cvo::lcm_map (it links the back end);
// the checks a received map passes are map_check.hpp's, in the wire library.
#include <cstdint>
#include <optional>
#include <string>

#include "cvo_lcm/map_t.hpp"
#include "libcvo/slam/mapper.hpp"

namespace cvo::lcm {

/// `epoch`: when the publishing back end started (map_t.epoch).
cvo_lcm::map_t to_message(const slam::Map& map, std::int64_t utime, std::int64_t epoch = 0);

/// One session's entry, as map_t and map_correction_t carry it.
cvo_lcm::map_session_t to_message(const slam::MapSession& session);
/// Back from an entry that map_check.hpp accepted (its correction a rigid transform).
slam::MapSession from_checked_message(const cvo_lcm::map_session_t& session);

/// Fails on another schema version or a pose that is not a rigid transform. Loops come back with
/// their keyframe ids in LoopClosure::from/to (node ids are the mapper's own, not on the wire).
std::optional<slam::Map> from_message(const cvo_lcm::map_t& message, std::string* error);

}  // namespace cvo::lcm
