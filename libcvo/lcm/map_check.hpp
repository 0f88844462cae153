#pragma once
// What makes a CVO_MAP usable, checked on the message itself: this schema version, and every pose
// in it (each session's correction, each keyframe's pose, each loop's measurement) a rigid
// transform. Without the back end's types, so that the tracker (map_decision.hpp) checks a map
// without linking the back end; map_conversion.hpp converts only what passes.
#include <string>

#include "cvo_lcm/map_t.hpp"

namespace cvo::lcm {

/// "" when `message` is usable; else why not ("cvo_lcm.map_t: keyframe 3 of session 7: ..."),
/// naming the first pose that is not a rigid transform.
std::string map_error(const cvo_lcm::map_t& message);

}  // namespace cvo::lcm
