#pragma once
// What cvo-trackerd's three threads share, and who writes each part. Everything else belongs to
// one thread's class: Acquisition (acquisition.hpp), Tracking (tracking.hpp), Publishing
// (publishing.hpp); Trackerd (trackerd.hpp) owns this and supervises them.
//
//   config, parameters, ring  made before the threads start; the ring is thread-safe
//   bus                       the key ring and signer (thread-safe), read from auth.key_file at start
//   counters                  each counter written by one thread, read by the publisher
//   session                   cvo-track (a new session when the camera comes back or changes)
//   correction                cvo-publish (each CVO_MAP_CORRECTION, CVO_MAP), read by cvo-track for the map pose
//   outbox                    made by cvo-track for its first camera, then thread-safe
//   notes, count_bad()        any thread but cvo-track (noting allocates: it only counts)
//   systemd                   READY/STOPPING/WATCHDOG from the supervisor, STATUS from cvo-publish
//   heartbeats, flags         one writer each
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "cvo_lcm/status_t.hpp"
#include "daemon/common/bus_auth.hpp"
#include "daemon/common/heartbeat.hpp"
#include "daemon/common/notes.hpp"
#include "daemon/common/systemd_notify.hpp"
#include "daemon/trackerd/frame_ring.hpp"
#include "daemon/trackerd/map_correction.hpp"
#include "daemon/trackerd/outbox.hpp"
#include "libcvo/config/config.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"

namespace cvo::daemon::trackerd {

struct Counters {
  std::atomic<std::int64_t> frames_tracked{0};
  std::atomic<std::int64_t> keyframes{0};
  std::atomic<std::int64_t> failed_frames{0};
  std::atomic<std::int64_t> source_gaps{0};
  std::atomic<std::int64_t> source_lost_frames{0};  // frames the source saw missing (FrameSource::lost_frames)
  std::atomic<std::int64_t> allocations_after_warmup{0};
  std::atomic<std::int64_t> bad_messages[cvo_lcm::status_t::NUM_BAD_KINDS]{};  // by BAD_* (frames, maps, requests)
  std::atomic<bool> source_connected{false};
};

/// The outbox is sized by the camera, so the tracking thread makes it on the first usable frame;
/// the publisher uses it once `ready` (release/acquire). `camera_size` (width << 32 | height) is
/// the camera tracked now: the publisher sizes its keyframe history for it.
struct OutboxHandoff {
  std::unique_ptr<Outbox> outbox;
  std::atomic<bool> ready{false};
  std::atomic<std::uint64_t> camera_size{0};
};

/// 64 random bits from the kernel, never 0 ("no session"); the tracking
/// thread may call it (getrandom(2) neither allocates nor blocks once the pool is ready).
std::int64_t new_session_id(std::uint64_t previous = 0);

struct Shared {
  explicit Shared(config::Config c);

  /// A refused message or frame, by BAD_*; noted at the log-rate policy (not from cvo-track).
  void count_bad(int kind, const std::string& what, const std::string& why);

  const config::Config config;
  const odometry::KeyframeOdometryParameters parameters;  // the tracker's (config::module_parameters)
  BusAuth bus;                                            // signs every publish; verifiers per receiver
  Notes notes{"cvo-trackerd"};
  const SystemdNotifier systemd;
  Counters counters;
  std::atomic<std::int64_t> session;
  MapCorrection correction;
  FrameRing ring;
  OutboxHandoff out;
  Heartbeat track_heartbeat, publish_heartbeat;
  std::atomic<bool> stop{false};           // the supervisor: acquisition stops
  std::atomic<bool> source_failed{false};  // cvo-acquire: the source cannot be opened (exit 1)
  std::atomic<bool> tracker_done{false};   // cvo-track drained the ring and closed the outbox
  std::atomic<bool> publisher_done{false};
};

}  // namespace cvo::daemon::trackerd
