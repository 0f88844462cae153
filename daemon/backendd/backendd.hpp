#pragma once
// cvo-backendd: two threads around libcvo's SLAM mapper (slam::Mapper, the same back end cvo-run
// --mode slam uses), each its own class, joined only by the work queue and a small shared state
// (shared.hpp says who writes what):
//
//   cvo-receive   Receiving (receiving.hpp): LCM CVO_KEYFRAME / CVO_LOCAL_GRAPH / their slices ->
//                 decoded once and checked -> the door -> the keyframe store (libcvo/store, durable
//                 before anything else happens) -> work queue; lost keyframes asked for again
//   cvo-backend   MapBuilding (map_building.hpp): work queue -> slam::Mapper (loop detection across
//                 every session, joins, keyframe-graph optimisation), each keyframe's local map into
//                 the occupancy grid; what changed published by its Publishing (publishing.hpp):
//                 CVO_MAP_CORRECTION, CVO_MAP, CVO_GRID, CVO_STATUS
//
// Backendd supervises them from the caller's thread (daemon::supervise). At start-up the store is
// read back and every record goes through the same door and path, so a restart resumes every session
// received before; what they make goes out once every one is in (the full CVO_MAP and each
// session's CVO_MAP_CORRECTION), not after each: a tracker sees the restarted back end's revisions
// leap once, in its new epoch.
//
// Localization (backendd.mode localization): the store is only read (read_store, as cvo-map reads
// it: never written, renamed or cut back), its records are the map; once they are applied the
// final global optimisation runs and the mapper becomes read only (slam::Mapper::localize_only).
// Every new session is localized in it; its keyframes are never stored and make no grid, and the
// grid published is the stored map's. A CVO_POSE whose state is LOST marks its session lost (and any
// CVO_POSE keeps its session live for the re-sent corrections).
//
// On SIGTERM/SIGINT/SIGHUP: what is already in the socket is taken in, the queue is drained within
// backendd.stop_timeout_s (map_building.hpp), a final global optimisation runs, the changed
// corrections and the final CVO_MAP are published, then the final CVO_GRID, exit 0. No record can
// stop the daemon (record_guard.hpp). CVO_STATUS counts them: records the mapper refused in
// bad_messages[BAD_CONTENT], records and steps skipped after a failure of the back end's own in
// failed_frames.
#include <memory>
#include <vector>

#include "daemon/backendd/map_building.hpp"
#include "daemon/backendd/receiving.hpp"
#include "daemon/backendd/shared.hpp"
#include "libcvo/config/config.hpp"
#include "libcvo/store/keyframe_store.hpp"

namespace cvo::daemon::backendd {

class Backendd {
 public:
  /// Opens the store (recovering its records) and the LCM provider, loads the vocabulary; throws
  /// io::InputError naming what is wrong.
  explicit Backendd(config::Config config);
  ~Backendd();
  Backendd(const Backendd&) = delete;
  Backendd& operator=(const Backendd&) = delete;

  /// Runs until SIGTERM/SIGINT; returns the exit status. block_stop_signals() must have been
  /// called before.
  int run();

 private:
  void open_store();
  void read_map_store();

  std::unique_ptr<Shared> shared_;
  std::unique_ptr<MapBuilding> map_building_;
  std::unique_ptr<Receiving> receiving_;
  std::vector<store::StoredRecord> recovered_;  // the store's records, let in by run()
};

}  // namespace cvo::daemon::backendd
