#include "libcvo/lcm/map_check.hpp"

#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {

std::string map_error(const cvo_lcm::map_t& m) {
  const std::string prefix = "cvo_lcm.map_t: ";
  if (m.version != cvo_lcm::map_t::SCHEMA_VERSION) return prefix + "schema version " + std::to_string(m.version);
  std::string why;
  for (const auto& s : m.sessions)
    if (!from_message(s.correction, &why)) return prefix + "session " + std::to_string(s.session) + ": " + why;
  for (const auto& k : m.keyframes)
    if (!from_message(k.pose, &why))
      return prefix + "keyframe " + std::to_string(k.id) + " of session " + std::to_string(k.session) + ": " + why;
  for (const auto& l : m.loops)
    if (!from_message(l.edge.measurement, &why))
      return prefix + "loop " + std::to_string(l.edge.from) + " -> " + std::to_string(l.edge.to) + ": " + why;
  return {};
}

}  // namespace cvo::lcm
