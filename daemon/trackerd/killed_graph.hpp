#pragma once
// The local graph of a killed session's newest keyframe (issue 48). A keyframe's local graph goes
// out when the next keyframe closes it, or at a clean end; a tracker killed in between leaves its
// newest keyframe in the spool without one, and the back end holds and acknowledges a keyframe only
// with its local graph (backendd/held_prefix.hpp). The next start hands that keyframe over with a
// graph of the keyframe alone: the frames tracked against it died with the process, so it adds no
// constraint, and the keyframe is then held, acknowledged and deleted from the spool like any other.
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace cvo::daemon::trackerd {

/// The encoded CVO_LOCAL_GRAPH (its auth trailer zero, as spooled) of the keyframe whose encoded
/// CVO_KEYFRAME is `keyframe`: its one node, the keyframe's frame, time and odometry pose; closed at
/// `utime`. nullopt when `keyframe` does not decode.
std::optional<std::vector<std::uint8_t>> graph_of_killed_keyframe(std::span<const std::uint8_t> keyframe,
                                                                  std::int64_t utime);

}  // namespace cvo::daemon::trackerd
