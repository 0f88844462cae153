#pragma once
// cvo-trackerd's wiring: three named threads around libcvo's KF-CVO tracker.
//
//   cvo-acquire   frame source (drivers/) -> FrameRing          re-opens a lost device with back-off
//   cvo-track     FrameRing -> KeyframeOdometry -> Outbox        SCHED_FIFO, pinned, no allocation
//   cvo-publish   Outbox -> LCM CVO_POSE / CVO_KEYFRAME / CVO_LOCAL_GRAPH, 1 Hz CVO_STATUS;
//                 CVO_MAP in -> MapCorrection (read by cvo-track for the map pose);
//                 CVO_KEYFRAME_REQUEST in -> what the back end missed, again from the
//                 KeyframeHistory of what was published (keyframe_history.hpp)
//
// The caller's thread (run()) waits for SIGTERM/SIGINT or the end of a finite source, pets the
// systemd watchdog while the workers are alive, and shuts down in order: acquisition stops, the
// tracker finishes the frames already in the ring and hands out the open local graph (so the back
// end has every tracked frame), the publisher flushes, then run() returns 0.
//
// Sessions (proto/pose_t.lcm): each start is a session with a random 64-bit id, carried by every
// message; frame indices and keyframe ids count from 0 in it. A source that comes back after a
// disconnection (a camera unplugged, re-initialised) is a new session: its odometry starts again at
// the first frame, so the old session's open local graph goes out first and the tracker, its
// keyframe numbering and the frame indices are reset (RingSlot::connection tells the tracker).
// CVO_MAP corrects the map pose only when it places the running session, is newer than the map
// applied last and moves the map frame plausibly (lcm::decide_map_correction); each refusal is
// counted by kind.
//
// Camera changes: frames of another camera (size or intrinsics) are refused as bad content until
// trackerd.camera_change_frames of them came in a row; then that camera is the tracker's, in a new
// session, with a tracker and keyframe slots of its size (the allocations this takes are noted, and
// warm-up starts again before allocations count in allocations_after_warmup).
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "cvo_lcm/status_t.hpp"
#include "daemon/common/systemd_notify.hpp"
#include "daemon/trackerd/frame_ring.hpp"
#include "daemon/trackerd/map_correction.hpp"
#include "daemon/trackerd/outbox.hpp"
#include "drivers/frame_source.hpp"
#include "libcvo/lcm/map_decision.hpp"
#include "libcvo/config/config.hpp"

namespace cvo::daemon::trackerd {

/// Counters shared by the threads; each is written by one thread and read by the publisher.
struct Counters {
  std::atomic<std::int64_t> frames_tracked{0};
  std::atomic<std::int64_t> keyframes{0};
  std::atomic<std::int64_t> failed_frames{0};
  std::atomic<std::int64_t> source_gaps{0};
  std::atomic<std::int64_t> source_lost_frames{0};  // frames the source saw missing (FrameSource::lost_frames)
  std::atomic<std::int64_t> allocations_after_warmup{0};
  std::atomic<std::int64_t> bad_messages[cvo_lcm::status_t::NUM_BAD_KINDS]{};  // by BAD_* (frames, CVO_MAP, requests)
  std::atomic<bool> source_connected{false};
};

class Trackerd {
 public:
  /// Checks the configuration and opens the LCM output; throws io::InputError (with a message
  /// that names the key or URL) when that cannot work. The frame source is opened by the
  /// acquisition thread, so a camera that is not plugged in yet is waited for, not fatal.
  explicit Trackerd(config::Config config);
  /// The same with another frame source than trackerd.source names (opened by the acquisition
  /// thread, as above): how tests drive the daemon with a camera that goes away and comes back.
  using SourceFactory = std::function<std::unique_ptr<drivers::FrameSource>()>;
  Trackerd(config::Config config, SourceFactory open_source);
  ~Trackerd();
  Trackerd(const Trackerd&) = delete;
  Trackerd& operator=(const Trackerd&) = delete;

  /// Runs until SIGTERM/SIGINT, or the source's end with trackerd.exit_on_eof; returns the exit
  /// status (0 clean, 1 when the source could not be opened at all in exit-on-eof mode).
  /// The caller must have called block_stop_signals() before any thread was started.
  int run();

 private:
  struct Pipeline;
  void acquire_loop();
  void track_loop();
  Pipeline* start_pipeline(const core::RgbdFrame& first);
  bool accept_camera(Pipeline& p, const core::RgbdFrame& frame);
  void change_camera(Pipeline& p, const core::RgbdFrame& first);
  void track_frame(Pipeline& p, const RingSlot& slot, Event& event);
  void publish_open_graph(Pipeline& p);
  void start_new_session(Pipeline& p);
  struct Publisher;
  void publish_loop();
  void publish_event(Publisher& out, const Event& event);
  void publish_keyframe(Publisher& out, const Event& event);
  void answer_request(Publisher& out, const void* data, int size);
  void publish_status(Publisher& out, std::int8_t state_override);
  void apply_map(const void* data, int size);
  void count_bad(int kind, const std::string& what, const std::string& why);  // by BAD_*; notes the first ones
  void note(const std::string& detail);  // logs to stderr, and CVO_STATUS.detail

  config::Config config_;
  SourceFactory open_source_;
  SystemdNotifier systemd_;
  Counters counters_;
  std::unique_ptr<FrameRing> ring_;
  MapCorrection correction_;
  lcm::AppliedCorrection applied_;  // the last CVO_MAP correction applied (publisher thread only)
  // The running session: written by the tracking thread (a new one when the camera comes back),
  // read by the publisher for CVO_MAP.
  std::atomic<std::int64_t> session_;

  std::atomic<bool> stop_{false};          // asks acquisition to stop
  std::atomic<bool> tracker_done_{false};  // the tracker drained the ring and closed the outbox
  std::atomic<bool> publisher_done_{false};
  std::atomic<bool> fatal_{false};         // the source could not be opened (exit-on-eof mode)
  std::atomic<std::int64_t> track_heartbeat_ns_{0}, publish_heartbeat_ns_{0};

  // Created by the tracking thread on the first usable frame (its size sizes every buffer; a camera
  // change resizes the tracking thread's own part and the keyframe slots); the publisher uses it
  // once pipeline_ready_ is set (release/acquire of the atomic).
  std::unique_ptr<Pipeline> pipeline_;
  std::atomic<bool> pipeline_ready_{false};
  // The size of the camera tracked (width << 32 | height): the publisher sizes its keyframe
  // history for it when a session starts.
  std::atomic<std::uint64_t> camera_size_{0};

  std::mutex detail_mutex_;
  std::string detail_;
};

}  // namespace cvo::daemon::trackerd
