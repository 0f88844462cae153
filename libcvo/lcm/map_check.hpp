#pragma once
// What makes a CVO_MAP or a CVO_MAP_CORRECTION usable, checked on the message itself: this schema
// version, every session entry's state and covariance what they must be, and every pose in it
// (each session's correction, each keyframe's pose, each loop's measurement and, in a correction,
// the other keyframe's pose) a rigid transform; a correction carries at most MAX_LOOPS loops.
// Without the back end's types, so that the tracker (map_decision.hpp) checks a map without
// linking the back end; map_conversion.hpp converts only what passes.
#include <string>

#include "cvo_lcm/map_correction_t.hpp"
#include "cvo_lcm/map_t.hpp"

namespace cvo::lcm {

/// "" when `message` is usable; else why not ("cvo_lcm.map_t: keyframe 3 of session 7: ..."),
/// naming the first pose that is not a rigid transform.
std::string map_error(const cvo_lcm::map_t& message);

/// The same for one session's correction ("cvo_lcm.map_correction_t: ...").
std::string correction_error(const cvo_lcm::map_correction_t& message);

}  // namespace cvo::lcm
