#pragma once
// cvo-backend: the work queue into libcvo's SLAM mapper (slam::Mapper, the same back end cvo-run
// --mode slam uses): loop detection across every session, joins, keyframe-graph optimisation; each
// keyframe's local map into the occupancy grid (mapping::Mapping); what changed published
// (Publishing, publishing.hpp). Merges and settled revisits are stored, and the records they make
// garbage discarded (libcvo/store/store_merges.hpp).
//
// No record can stop the daemon: what the mapper cannot apply is noted and skipped, and so is a
// record or step it fails on (record_guard.hpp), never the process or the map.
//
// A signal stop ends within backendd.stop_timeout_s (below the unit's TimeoutStopSec), whatever
// waits: records are applied during its first half; what still waits then is left, since every
// record is in the store before it is queued, and the next start's replay applies it. The final
// global optimisation gets the time up to the last quarter, cut short at its last accepted step (or
// skipped) when that runs out; the last quarter publishes the final corrections, map and grid. A
// log that ended (exit_on_eof) is worked through whole.
#include <cstdint>
#include <optional>
#include <string>

#include "daemon/backendd/publishing.hpp"
#include "daemon/backendd/record_guard.hpp"
#include "daemon/backendd/shared.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/mapping/mapping.hpp"
#include "libcvo/slam/mapper.hpp"
#include "libcvo/store/keyframe_store.hpp"
#include "libcvo/store/message_door.hpp"
#include "libcvo/store/store_merges.hpp"

namespace cvo::daemon::backendd {

class MapBuilding {
 public:
  /// Opens the provider CVO_MAP and the rest go to (publishing_good() says whether it could).
  MapBuilding(Shared& shared, loop_closure::Vocabulary vocabulary);

  [[nodiscard]] bool publishing_good() { return publishing_.good(); }
  /// The store merges and settlements are kept in (none in localization mode: it is only read).
  void keep_merges_in(store::KeyframeStore& store) { merges_.emplace(store); }
  /// The thread's body: until the queue is drained after cvo-receive ended, or a stop's time for
  /// records is over; then the final optimisation, map, grid and notes.
  void run();

 private:
  void process(QueuedRecord& queued);
  void process_record(QueuedRecord& queued);
  void localize_when_stored();
  void start_localizing();
  void settle();
  void replayed();
  std::optional<store::RecordValue> value_of(QueuedRecord& queued, std::string* error);
  void apply_keyframe(const lcm::Keyframe& keyframe, const QueuedRecord& queued);
  void add_to_grid(const lcm::Keyframe& keyframe);
  void apply_merge(const slam::KeyframeMerge& merge, const std::optional<store::RecordRef>& stored);
  void apply_settled(const slam::SettledEdge& edge, const std::optional<store::RecordRef>& stored);
  void apply_tally(const slam::SessionTally& tally, const std::optional<store::RecordRef>& stored);
  void apply_local_graph(const store::LocalGraphRecord& record, const QueuedRecord& queued);
  void mark_lost(core::SessionId session);
  // A keyframe the mapper merged: its merge into the store, its own record discarded.
  void store_merge(const slam::KeyframeMerge& merge, bool replayed);
  // Compaction waits while records wait in the store: their references must not age past two.
  [[nodiscard]] bool may_compact() const { return shared_.counters.waiting_in_store == 0; }
  void leave_waiting_records();
  void finish();
  void final_optimisation();
  void closing_notes();

  Shared& shared_;
  RecordGuard guard_;  // each record and step costs at most itself
  slam::Mapper mapper_;
  mapping::Mapping grid_map_;  // the occupancy grid of the mapper's map (CVO_GRID)
  Publishing publishing_;
  std::optional<store::StoreMerges> merges_;  // none in localization mode: the store is only read
  std::int64_t local_graphs_ = 0;
  std::size_t not_mapped_ = 0;  // keyframes the occupancy grid refused
};

}  // namespace cvo::daemon::backendd
