#include "daemon/backendd/map_summary.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace cvo::daemon::backendd {

using Clock = std::chrono::steady_clock;

std::string fixed(double value, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, value);
  return text;
}

MapSummary summarise(const slam::Map& map) {
  MapSummary s;
  s.sessions = map.sessions.size();
  s.placed = static_cast<std::size_t>(
      std::count_if(map.sessions.begin(), map.sessions.end(), [](const auto& m) { return m.placed; }));
  s.keyframes = map.keyframes.size();
  s.loops = map.loops.size();
  s.loops_across = static_cast<std::size_t>(
      std::count_if(map.loops.begin(), map.loops.end(), [](const auto& l) { return l.from_session != l.to_session; }));
  s.revision = map.revision;
  return s;
}

std::string text(const MapSummary& s) {
  return std::to_string(s.sessions) + " sessions (" + std::to_string(s.placed) + " placed), " +
         std::to_string(s.keyframes) + " keyframes, " + std::to_string(s.loops) + " loops (" +
         std::to_string(s.loops_across) + " across sessions), map revision " + std::to_string(s.revision);
}

std::string text(const char* channel, const Sent& s) {
  return std::to_string(s.messages) + " " + channel + " sent (" + std::to_string(s.bytes_last) + " bytes the last, " +
         std::to_string(s.bytes_max) + " at most)";
}

std::string text(const GridSummary& g, const mapping::MappingStatistics& s) {
  if (g.published == 0) return "no grid yet (" + std::to_string(s.keyframes) + " keyframes mapped)";
  return "grid revision " + std::to_string(g.revision) + " (" + std::to_string(s.placed) + " of " +
         std::to_string(s.keyframes) + " keyframes mapped, " + fixed(static_cast<double>(s.local_map_bytes) / 1e6, 1) +
         " MB of local maps, " + std::to_string(g.bytes) + " bytes on CVO_GRID)";
}

std::string join_text(const slam::Map& map, core::SessionId session, std::optional<Clock::time_point> first_arrival) {
  const auto s =
      std::find_if(map.sessions.begin(), map.sessions.end(), [&](const auto& m) { return m.session == session; });
  const std::int64_t at = s != map.sessions.end() ? s->joined_at_keyframe : -1;
  if (s != map.sessions.end() && s->visitor) {  // its keyframes are in no map: arrival time only
    std::string out =
        "session " + core::session_name(session) + " localized in the stored map at its keyframe " + std::to_string(at);
    if (!first_arrival) return out;
    return out + " (" + fixed(std::chrono::duration<double>(Clock::now() - *first_arrival).count(), 2) +
           " s after its first keyframe arrived)";
  }
  double first = std::numeric_limits<double>::quiet_NaN(), joined = first;
  for (const auto& k : map.keyframes) {
    if (k.session != session) continue;
    if (std::isnan(first)) first = k.timestamp;  // by id: the session's first keyframe
    if (k.id == at) joined = k.timestamp;
  }
  // A revisit's keyframes may all be merged into the map's already: then the map lists none of its.
  const std::string sensor_time = std::isnan(joined - first)
                                      ? "its keyframes merged into the map's"
                                      : fixed(joined - first, 2) + " s of sensor time after its first keyframe";
  std::string out = "session " + core::session_name(session) + " joined the map at its keyframe " + std::to_string(at) +
                    " (" + sensor_time + ", ";
  if (!first_arrival) return out + "its first keyframe replayed from the store)";
  return out + fixed(std::chrono::duration<double>(Clock::now() - *first_arrival).count(), 2) +
         " s after its first keyframe arrived)";
}

}  // namespace cvo::daemon::backendd
