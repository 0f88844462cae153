#include "libcvo/lcm/map_conversion.hpp"

#include <algorithm>

#include "libcvo/lcm/map_check.hpp"
#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {

cvo_lcm::map_session_t to_message(const slam::MapSession& s) {
  cvo_lcm::map_session_t e{};
  e.session = s.session;
  e.placed = s.placed;
  e.piece = s.piece;
  e.keyframes = static_cast<std::int32_t>(s.keyframes);
  e.joined_at_keyframe = s.joined_at_keyframe;
  e.correction = to_message(s.correction);
  e.state = static_cast<std::int8_t>(s.state);
  e.visitor = s.visitor;
  e.last_match_utime = s.last_match_time >= 0 ? to_utime(s.last_match_time) : 0;
  e.covariance_keyframe = s.keyframe_covariance ? s.covariance_keyframe : -1;
  matrix6_to_message(s.keyframe_covariance.value_or(core::Matrix6d::Zero()), e.keyframe_covariance);
  return e;
}

slam::MapSession from_checked_message(const cvo_lcm::map_session_t& s) {
  slam::MapSession e;
  e.session = s.session;
  e.placed = s.placed != 0;
  e.piece = s.piece;
  e.keyframes = static_cast<std::size_t>(std::max(0, s.keyframes));
  e.joined_at_keyframe = s.joined_at_keyframe;
  e.correction = *from_message(s.correction, nullptr);
  e.state = static_cast<core::LocalizationState>(s.state);
  e.visitor = s.visitor != 0;
  e.last_match_time = s.last_match_utime > 0 ? from_utime(s.last_match_utime) : -1;
  if (s.covariance_keyframe >= 0) {
    e.covariance_keyframe = s.covariance_keyframe;
    e.keyframe_covariance = matrix6_from_message(s.keyframe_covariance);
  }
  return e;
}

cvo_lcm::map_t to_message(const slam::Map& map, std::int64_t utime, std::int64_t epoch) {
  cvo_lcm::map_t m{};
  m.version = cvo_lcm::map_t::SCHEMA_VERSION;
  m.utime = utime;
  m.epoch = epoch;
  m.revision = static_cast<std::int64_t>(map.revision);
  for (const auto& s : map.sessions) {
    m.sessions.push_back(to_message(s));
    m.robots.push_back(s.robot);
  }
  for (const auto& k : map.keyframes)
    m.keyframes.push_back({k.session, k.id, to_utime(k.timestamp), to_message(k.pose)});
  for (const auto& l : map.loops) {
    cvo_lcm::map_loop_t loop{};
    loop.from_session = l.from_session;
    loop.to_session = l.to_session;
    loop.edge.from = l.from_id;
    loop.edge.to = l.to_id;
    loop.edge.measurement = to_message(l.loop.measurement);
    matrix6_to_message(l.loop.information, loop.edge.information);
    m.loops.push_back(loop);
  }
  m.num_sessions = static_cast<std::int32_t>(m.sessions.size());
  m.num_keyframes = static_cast<std::int32_t>(m.keyframes.size());
  m.num_loops = static_cast<std::int32_t>(m.loops.size());
  return m;
}

std::optional<slam::Map> from_message(const cvo_lcm::map_t& m, std::string* error) {
  if (std::string why = map_error(m); !why.empty()) {
    if (error != nullptr) *error = std::move(why);
    return std::nullopt;
  }
  // Every pose below converts: map_error checked each.
  slam::Map map;
  map.revision = static_cast<std::uint64_t>(m.revision);
  for (std::size_t i = 0; i < m.sessions.size(); ++i) {
    map.sessions.push_back(from_checked_message(m.sessions[i]));
    map.sessions.back().robot = m.robots[i];
  }
  for (const auto& k : m.keyframes)
    map.keyframes.push_back({k.session, k.id, from_utime(k.utime), *from_message(k.pose, nullptr)});
  for (const auto& l : m.loops) {
    slam::MapLoop loop;
    loop.from_session = l.from_session;
    loop.to_session = l.to_session;
    loop.from_id = l.edge.from;
    loop.to_id = l.edge.to;
    loop.loop.from = l.edge.from;
    loop.loop.to = l.edge.to;
    loop.loop.measurement = *from_message(l.edge.measurement, nullptr);
    loop.loop.information = matrix6_from_message(l.edge.information);
    map.loops.push_back(loop);
  }
  return map;
}

}  // namespace cvo::lcm
