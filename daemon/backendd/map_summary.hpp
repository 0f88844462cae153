#pragma once
// What cvo-backendd says of its map, its channels and its grid: for CVO_STATUS, systemd's STATUS
// and the closing note (publishing.hpp, map_building.hpp).
#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "libcvo/core/session.hpp"
#include "libcvo/mapping/mapping.hpp"
#include "libcvo/slam/mapper.hpp"

namespace cvo::daemon::backendd {

/// `value` with `digits` decimals.
std::string fixed(double value, int digits);

struct MapSummary {
  std::size_t sessions = 0, placed = 0, keyframes = 0, loops = 0, loops_across = 0;
  std::uint64_t revision = 0;
};
MapSummary summarise(const slam::Map& map);
std::string text(const MapSummary& s);

// What a channel of the map has sent: messages and their encoded bytes (the last, the largest).
struct Sent {
  std::size_t messages = 0, bytes_last = 0, bytes_max = 0;
  void add(std::size_t bytes) {
    ++messages;
    bytes_last = bytes;
    bytes_max = std::max(bytes_max, bytes);
  }
};
std::string text(const char* channel, const Sent& s);

// What CVO_GRID has sent, and what the mapping costs.
struct GridSummary {
  std::optional<std::chrono::steady_clock::time_point> last;  // when the last CVO_GRID went
  std::int64_t revision = -1;                                 // of the last CVO_GRID
  std::size_t published = 0, bytes = 0;                       // CVO_GRIDs sent; the last one's encoded size
  std::size_t places = 0;                                     // place() calls that changed the grid
  double place_ms_total = 0, place_ms_max = 0;
};
std::string text(const GridSummary& g, const mapping::MappingStatistics& s);

/// How long a new session took to find its place in the map, after its first keyframe: in sensor
/// time (what the robot had to see) and on this machine (what the back end took, with its queue;
/// nullopt `first_arrival`: replayed from the store).
std::string join_text(const slam::Map& map, core::SessionId session,
                      std::optional<std::chrono::steady_clock::time_point> first_arrival);

}  // namespace cvo::daemon::backendd
