#pragma once
// What cvo-backend publishes of the map, on its own thread (MapBuilding owns this): after each
// change CVO_MAP_CORRECTION for each session whose entry changed (O(1) bytes each), each live
// session's again once a status period, a session's at once when the store holds more of it than it
// was told (held_prefix.hpp; between two records), and the full CVO_MAP at most once
// backendd.map_period_s while it changes, at once after a join, within a second after a loop
// closure (map_schedule.hpp); each full map's poses placed into the occupancy grid -> CVO_GRID at
// most once a second while it changes, at once with a loop's map when it moved keyframes;
// CVO_STATUS once a status period. While the store is replayed nothing goes out: what its records
// make goes once every one is in.
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "daemon/backendd/map_schedule.hpp"
#include "daemon/backendd/map_summary.hpp"
#include "daemon/backendd/record_guard.hpp"
#include "daemon/backendd/shared.hpp"
#include "libcvo/mapping/mapping.hpp"
#include "libcvo/slam/mapper.hpp"

namespace cvo::daemon::backendd {

class Publishing {
 public:
  /// Opens the provider of backendd.publish_url (good() says whether it could).
  Publishing(Shared& shared, const slam::Mapper& mapper, mapping::Mapping& grid, const RecordGuard& guard);

  [[nodiscard]] bool good() { return lcm_.good(); }

  /// After a change that may have touched `touched` only (nullopt: every session): the corrections
  /// that changed, the full map when due. During the store's replay only what it joined is kept.
  void changes(std::optional<core::SessionId> touched, const std::vector<std::int64_t>& joined, bool after_loop);
  /// The store's last record is applied: its map goes out at once, with each session's correction.
  void replayed();
  /// Every session's correction and the full map, changed or not (localization's start, the stop).
  void whole_map();
  /// The mapper's optimisations so far are published (the corrections need not go again for them).
  void optimisations_published() { optimisations_ = mapper_.optimisations(); }
  /// From cvo-backend's loop: what is due by time (map_schedule.hpp), the grid once its second has
  /// passed, CVO_STATUS once its period has.
  void due();
  void grid_due();
  void status_due();
  /// The final CVO_GRID, changed or not; the last CVO_STATUS (`state`).
  void grid(bool after_loop);
  void status(std::int8_t state);

  /// A session's record came (`at`: live input) or its tracker said it is lost.
  void seen(core::SessionId session, Clock::time_point at) { schedule_.seen(session, at); }
  void lost(core::SessionId session) { schedule_.lost(session); }
  /// A session's first keyframe came (`arrived`; nullopt: replayed), for the note of its join.
  void first_keyframe(core::SessionId session, std::optional<Clock::time_point> arrived) {
    first_arrival_.try_emplace(session, arrived);
  }
  void processed() { ++processed_; }

  /// For the closing note.
  [[nodiscard]] const MapSummary& summary() const { return summary_; }
  [[nodiscard]] const Sent& corrections_sent() const { return corrections_; }
  [[nodiscard]] const Sent& maps_sent() const { return maps_; }
  [[nodiscard]] const GridSummary& grid_summary() const { return grid_; }
  [[nodiscard]] const std::vector<std::string>& joins() const { return joins_; }

 private:
  // Those of `sessions` whose entry changed (`again`: each, changed or not).
  void corrections(const std::vector<core::SessionId>& sessions, bool again);
  void map(const std::vector<std::int64_t>& joined, bool after_loop);
  void place_in_grid(const slam::Map& map, bool after_loop);
  void note_grid(const mapping::MapGrid& grid, bool first, bool after_loop);

  Shared& shared_;
  const slam::Mapper& mapper_;
  mapping::Mapping& grid_map_;  // the occupancy grid of the mapper's map
  const RecordGuard& guard_;    // what it refused and failed, for CVO_STATUS
  ::lcm::LCM lcm_;              // CVO_MAP_CORRECTION, CVO_MAP, CVO_GRID and CVO_STATUS
  MapSchedule schedule_;        // when which of the map goes out
  // CVO_MAP's epoch: revisions count from the start of this process, and a tracker takes a newer
  // epoch's maps after a restart of the back end instead of refusing them as stale.
  const std::int64_t epoch_;
  std::size_t optimisations_ = 0;            // the mapper's when corrections last went out
  Sent corrections_, maps_;                  // CVO_MAP_CORRECTION, CVO_MAP
  std::vector<std::int64_t> replay_joined_;  // sessions the store's records joined, noted with its map
  // When each session's first keyframe arrived (nullopt: it was replayed from the store).
  std::map<core::SessionId, std::optional<Clock::time_point>> first_arrival_;
  std::vector<std::string> joins_;  // every join noted, repeated in the closing note
  MapSummary summary_;              // of the last map published
  GridSummary grid_;
  bool grid_changed_ = false;  // since the last CVO_GRID
  std::int64_t processed_ = 0, processed_at_last_status_ = 0;
  Clock::time_point last_status_ = Clock::now();
};

}  // namespace cvo::daemon::backendd
