#pragma once
// cvo-trackerd: three threads around libcvo's KF-CVO tracker, each its own class, joined only by
// the FrameRing, the Outbox and a small shared state (shared.hpp says who writes what):
//
//   cvo-acquire   Acquisition: frame source (drivers/) -> FrameRing; re-opens a lost device
//   cvo-track     Tracking: FrameRing -> KeyframeOdometry -> Outbox; SCHED_FIFO, no allocation
//   cvo-publish   Publishing: Outbox -> LCM CVO_POSE / CVO_KEYFRAME / CVO_LOCAL_GRAPH, CVO_STATUS;
//                 CVO_MAP_CORRECTION, CVO_MAP in -> MapCorrection; CVO_KEYFRAME_REQUEST in -> the KeyframeHistory
//
// Trackerd supervises them from the caller's thread (daemon::supervise): it waits for SIGTERM,
// SIGINT or SIGHUP, or the end of a finite source, pets the systemd watchdog while the workers
// beat, and shuts down in order: acquisition stops, the tracker finishes the frames already in
// the ring and hands out the open local graph (so the back end has every tracked frame), the
// publisher flushes, then run() returns 0.
//
// Sessions (proto/pose_t.lcm): each start is a session with a random 64-bit id, carried by every
// message; frame indices and keyframe ids count from 0 in it. A camera that comes back after a
// disconnection, or another camera, is a new session (tracking.hpp).
#include <memory>

#include "daemon/trackerd/acquisition.hpp"
#include "daemon/trackerd/shared.hpp"
#include "libcvo/config/config.hpp"

namespace cvo::daemon::trackerd {

class Trackerd {
 public:
  /// Checks the configuration, the spool directory (Spool::unusable) and opens the LCM output;
  /// throws io::InputError (with a message that names the key or URL) when that cannot work. The frame source is opened
  /// by the acquisition thread, so a camera that is not plugged in yet is waited for, not fatal.
  explicit Trackerd(config::Config config);
  /// The same with another frame source than trackerd.source names (opened by the acquisition
  /// thread, as above): how tests drive the daemon with a camera that goes away and comes back.
  Trackerd(config::Config config, SourceFactory open_source);
  ~Trackerd();
  Trackerd(const Trackerd&) = delete;
  Trackerd& operator=(const Trackerd&) = delete;

  /// Runs until a stop signal, or the source's end with trackerd.exit_on_eof; returns the exit
  /// status (0 clean, 1 when the source could not be opened at all in exit-on-eof mode). The stop
  /// signals must be blocked in every thread (daemon::block_stop_signals) before it starts.
  int run();

 private:
  void closing_note();

  std::unique_ptr<Shared> shared_;
  SourceFactory open_source_;
};

}  // namespace cvo::daemon::trackerd
