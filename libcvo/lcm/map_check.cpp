#include "libcvo/lcm/map_check.hpp"

#include "cvo_lcm/pose_t.hpp"
#include "libcvo/core/information.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {
namespace {

// "" when the entry and its robot ("": not known) are usable, else why not, after `prefix`.
std::string session_error(const std::string& prefix, const cvo_lcm::map_session_t& s, const std::string& robot) {
  const std::string session = prefix + "session " + std::to_string(s.session) + ": ";
  if (!robot.empty())
    if (auto why = core::robot_name_error(robot); !why.empty()) return session + why;
  std::string why;
  if (!from_message(s.correction, &why)) return session + why;
  if (s.state < cvo_lcm::pose_t::STATE_LOCALIZING || s.state > cvo_lcm::pose_t::STATE_LOST)
    return session + "state " + std::to_string(s.state);
  if (s.covariance_keyframe >= 0)
    // A covariance is what an information matrix must be: finite, symmetric, positive semi-definite.
    if (const auto check = core::check_information(matrix6_from_message(s.keyframe_covariance)); !check.ok())
      return session + "keyframe covariance: " + check.why();
  return {};
}

}  // namespace

std::string map_error(const cvo_lcm::map_t& m) {
  const std::string prefix = "cvo_lcm.map_t: ";
  if (m.version != cvo_lcm::map_t::SCHEMA_VERSION) return prefix + "schema version " + std::to_string(m.version);
  std::string why;
  if (m.robots.size() != m.sessions.size())
    return prefix + std::to_string(m.robots.size()) + " robots for " + std::to_string(m.sessions.size()) + " sessions";
  for (std::size_t i = 0; i < m.sessions.size(); ++i)
    if (std::string bad = session_error(prefix, m.sessions[i], m.robots[i]); !bad.empty()) return bad;
  for (const auto& k : m.keyframes)
    if (!from_message(k.pose, &why))
      return prefix + "keyframe " + std::to_string(k.id) + " of session " + std::to_string(k.session) + ": " + why;
  for (const auto& l : m.loops)
    if (!from_message(l.edge.measurement, &why))
      return prefix + "loop " + std::to_string(l.edge.from) + " -> " + std::to_string(l.edge.to) + ": " + why;
  return {};
}

std::string correction_error(const cvo_lcm::map_correction_t& m) {
  const std::string prefix = "cvo_lcm.map_correction_t: ";
  if (m.version != cvo_lcm::map_correction_t::SCHEMA_VERSION)
    return prefix + "schema version " + std::to_string(m.version);
  if (m.num_loops > cvo_lcm::map_correction_t::MAX_LOOPS)
    return prefix + std::to_string(m.num_loops) + " loops, more than " +
           std::to_string(cvo_lcm::map_correction_t::MAX_LOOPS);
  if (std::string bad = session_error(prefix, m.session, m.robot); !bad.empty()) return bad;
  std::string why;
  for (const auto& l : m.loops) {
    const std::string loop = prefix + "loop of keyframe " + std::to_string(l.keyframe) + " to keyframe " +
                             std::to_string(l.other_keyframe) + " of session " + std::to_string(l.other_session) + ": ";
    if (!from_message(l.measurement, &why)) return loop + why;
    if (!from_message(l.other_pose, &why)) return loop + "the other keyframe's pose: " + why;
  }
  return {};
}

}  // namespace cvo::lcm
