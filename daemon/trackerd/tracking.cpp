#include "daemon/trackerd/tracking.hpp"

#include <chrono>
#include <string>

#include "daemon/common/realtime.hpp"
#include "libcvo/core/session.hpp"
#include "program/allocation_counter.hpp"

namespace cvo::daemon::trackerd {
namespace {

using namespace std::chrono_literals;
using program::thread_allocations;

constexpr std::size_t kOutboxEvents = 64;  // 2 s at 30 Hz: the publisher may stall that long
constexpr std::size_t kPoolSlots = 8;      // keyframes / local graphs in flight to the publisher

// Images of the intrinsics' size.
bool images_fit(const core::RgbdFrame& frame) {
  const auto& k = frame.intrinsics;
  return frame.bgr.cols == k.width && frame.bgr.rows == k.height && frame.depth.cols == k.width &&
         frame.depth.rows == k.height;
}

// A frame of valid intrinsics with images of their size: one a pipeline can be made for.
// (validate() allocates its message only for invalid intrinsics, which sources refuse first.)
bool usable(const core::RgbdFrame& frame) { return images_fit(frame) && frame.intrinsics.validate().empty(); }

std::uint64_t packed_size(int width, int height) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(width)) << 32) | static_cast<std::uint32_t>(height);
}

std::string size_name(const core::Intrinsics& k) { return std::to_string(k.width) + "x" + std::to_string(k.height); }

}  // namespace

void Tracking::run() {
  name_this_thread("cvo-track");
  const auto& t = shared_.config.trackerd;
  if (t.realtime_priority > 0)
    if (const auto why = make_this_thread_realtime(t.realtime_priority); !why.empty())
      shared_.notes.note("warning: " + why + "; tracking at normal priority");
  if (t.cpu >= 0)
    if (const auto why = pin_this_thread(t.cpu); !why.empty()) shared_.notes.note("warning: " + why);

  while (true) {
    shared_.track_heartbeat.beat();
    RingSlot* slot = shared_.ring.begin_read(100ms);
    if (slot == nullptr) {
      if (shared_.ring.drained()) break;
      continue;
    }
    if (tracker_) follow_connection(*slot);
    if (!(tracker_ ? accept_camera(slot->frame) : start(slot->frame))) {  // counted, not noted: no allocation
      ++shared_.counters.bad_messages[cvo_lcm::status_t::BAD_CONTENT];
      shared_.ring.skip_read();
      continue;
    }
    slot->frame.index -= first_index_;  // frame indices count from 0 in a session
    Event event;
    track(*slot, event);
    shared_.ring.end_read();  // this frame's slot is kept: the next frame may make it a keyframe
    const bool lost = event.pose.state == core::LocalizationState::kLost;
    outbox_->push(event, t.deterministic);  // when full, dropped: counted, with what it carried
    ++session_frames_;
    ++shared_.counters.frames_tracked;
    if (lost) {  // the odometry failed: the next frame is the first of a new session
      first_index_ += static_cast<std::uint64_t>(event.pose.frame_index) + 1;
      start_new_session();
    }
    count_allocations();
  }
  if (tracker_) {
    end_session();  // the back end gets every tracked frame
    outbox_->close();
  }
  shared_.tracker_done = true;
}

// The tracker and the outbox for the first usable frame's camera; false (counted) for a frame that
// cannot be tracked.
bool Tracking::start(const core::RgbdFrame& first) {
  if (!usable(first)) return false;
  const auto& k = first.intrinsics;
  const auto& p = shared_.parameters;
  camera_ = k;
  tracker_ = std::make_unique<odometry::KeyframeOdometry>(k.width, k.height, p);
  shared_.out.outbox = std::make_unique<Outbox>(kOutboxEvents, kPoolSlots, k.width, k.height, p.odometry.max_points,
                                                p.tracking.local_graph_capacity);
  outbox_ = shared_.out.outbox.get();
  shared_.out.camera_size = packed_size(k.width, k.height);
  shared_.out.ready = true;
  return true;
}

// A new connection of the source is a new session; acquisition counts its frames from 0 again.
void Tracking::follow_connection(const RingSlot& slot) {
  if (slot.connection == connection_) return;
  if (session_frames_ > 0) start_new_session();
  connection_ = slot.connection;
  first_index_ = 0;
}

// Whether `frame` may be tracked: it comes from the tracker's camera, or from another camera whose
// frames have now come trackerd.camera_change_frames times in a row, and the tracker re-initialises
// for it. A lone frame of another camera is refused and does not disturb tracking.
bool Tracking::accept_camera(const core::RgbdFrame& frame) {
  if (frame.intrinsics == camera_) {  // validated when the tracker was made
    if (!images_fit(frame)) return false;
    other_frames_ = 0;
    return true;
  }
  if (!usable(frame)) return false;
  if (other_frames_ == 0 || !(frame.intrinsics == other_camera_)) {
    other_camera_ = frame.intrinsics;
    other_frames_ = 0;
  }
  if (++other_frames_ < shared_.config.trackerd.camera_change_frames) return false;
  change_camera(frame);
  return true;
}

// Another camera (a new size or new intrinsics) for good: its frames start a new session from
// `first`; a new size needs a tracker and keyframe slots of that size. That allocation is the
// camera change's, reported once here, and warm-up starts again before allocations count as defects.
void Tracking::change_camera(const core::RgbdFrame& first) {
  const core::Intrinsics& k = first.intrinsics;
  const std::int64_t allocations_before = thread_allocations();
  const std::string from = size_name(camera_);
  if (session_frames_ > 0) start_new_session();  // the old session's open local graph goes out first
  const bool resized = k.width != camera_.width || k.height != camera_.height;
  camera_ = k;
  if (resized) {
    tracker_.reset();  // before the new one: never both in memory
    tracker_ = std::make_unique<odometry::KeyframeOdometry>(k.width, k.height, shared_.parameters);
    outbox_->resize_keyframe_images(k.width, k.height);
    shared_.out.camera_size = packed_size(k.width, k.height);
  }
  first_index_ = first.index;
  other_frames_ = 0;
  defects_before_ = shared_.counters.allocations_after_warmup;
  warm_frames_ = 0;
  shared_.notes.note("camera changed (" + from + " to " + size_name(k) + ", fx " + std::to_string(k.fx) + ") for " +
                     std::to_string(shared_.config.trackerd.camera_change_frames) +
                     " frames in a row: tracking again in session " + core::session_name(shared_.session.load()) +
                     (resized ? "; the pipeline for the new size took " +
                                    std::to_string(thread_allocations() - allocations_before) +
                                    " allocations (not counted as realtime defects: warm-up again)"
                              : ""));
}

// One frame through KF-CVO into an event: what CVO_POSE says, and what the frame closed and made.
void Tracking::track(const RingSlot& slot, Event& event) {
  const core::RgbdFrame& frame = slot.frame;
  const odometry::TrackStep step = tracker_->track(frame);
  event.session = shared_.session.load(std::memory_order_relaxed);
  PoseEvent& e = event.pose;
  const MapPlacement placement = shared_.correction.get(event.session);
  e.frame_index = static_cast<std::int64_t>(frame.index);
  e.timestamp = frame.timestamp;
  e.received = slot.received;
  e.status = step.status;
  e.odom_pose = step.published_pose();  // the smooth pose (smooth_position.hpp); keyframes keep the tracked one
  e.map_pose = placement.T_map_odom * e.odom_pose;
  e.keyframe_odom_pose = step.new_keyframe ? std::optional<core::SE3>(step.new_keyframe->pose) : std::nullopt;
  e.map_placed = placement.placed;
  e.has_map_pose = placement.placed || odometry_until_localized_;
  e.map_epoch = placement.epoch;
  e.map_revision = placement.revision;
  e.state = step.lost          ? core::LocalizationState::kLost
            : placement.placed ? core::LocalizationState::kLocalized
                               : core::LocalizationState::kLocalizing;
  e.since_match_s = placement.last_match_time >= 0 ? frame.timestamp - placement.last_match_time : -1;
  e.inner_product = step.inner_product;
  e.gamma_keyframe = step.gamma;
  e.iterations = step.iterations;
  e.points = static_cast<int>(step.points);
  e.keyframe_id = step.keyframe_id;
  e.is_keyframe = step.keyframe;
  e.relative_covariance = step.relative_covariance;
  e.covariance = map_pose_covariance(frame, step, placement);
  if (!step.tracked()) ++shared_.counters.failed_frames;
  hand_over(step, event);
}

// The map pose's covariance: the back end's covariance of a keyframe's map pose composed with the
// odometry since (libcvo/odometry/pose_covariance.hpp); before the session is placed, or when the
// back end gives none for a keyframe still held, the odometry pose's own (since the first frame).
core::Matrix6d Tracking::map_pose_covariance(const core::RgbdFrame& frame, const odometry::TrackStep& step,
                                             const MapPlacement& placement) {
  if (const auto& k = step.new_keyframe) {  // frame n itself (the first, a restart) or frame n-1
    const bool itself = k->frame.index == frame.index;
    keyframe_covariances_.add(k->id, k->pose, itself ? step.odometry_covariance : previous_odometry_covariance_);
  }
  previous_odometry_covariance_ = step.odometry_covariance;
  if (placement.placed && placement.keyframe_covariance)
    if (const auto c = keyframe_covariances_.map_pose_covariance(
            placement.covariance_keyframe, *placement.keyframe_covariance, step.pose, step.odometry_covariance))
      return *c;
  return step.odometry_covariance;
}

// The closed local graph and the new keyframe into preallocated outbox slots (copies within
// capacity: no allocation). One that finds no slot (the publisher is behind) is counted lost by the
// outbox; a replay (deterministic) waits for one instead.
void Tracking::hand_over(const odometry::TrackStep& step, Event& event) {
  const bool wait = shared_.config.trackerd.deterministic;
  if (const auto& g = step.closed_graph; g && (event.graph_slot = outbox_->acquire_graph_slot(wait)) >= 0) {
    auto& slot = outbox_->graph(event.graph_slot);
    slot.keyframe_id = g->keyframe_id;
    slot.graph = *g->graph;
  }
  if (!step.new_keyframe) return;
  ++shared_.counters.keyframes;
  if ((event.keyframe_slot = outbox_->acquire_keyframe_slot(wait)) < 0) return;
  const odometry::NewKeyframe& k = *step.new_keyframe;
  auto& slot = outbox_->keyframe(event.keyframe_slot);
  slot.id = k.id;
  slot.pose = k.pose;
  slot.frame.index = k.frame.index;
  slot.frame.timestamp = k.frame.timestamp;
  slot.frame.depth_timestamp = k.frame.depth_timestamp;
  slot.frame.intrinsics = k.frame.intrinsics;
  k.frame.bgr.copyTo(slot.frame.bgr);  // same-sized images: no allocation
  k.frame.depth.copyTo(slot.frame.depth);
  slot.cloud = *k.cloud;  // same capacity: copies points, no allocation
}

// The running session ends: its open local graph goes out (waiting for room is harmless here: the
// source has ended or was away), and the ring may have the previous frame's slot back.
void Tracking::end_session() {
  if (const auto open = tracker_->finish()) {
    Event event;
    event.session = shared_.session.load(std::memory_order_relaxed);
    event.has_pose = false;
    event.graph_slot = outbox_->acquire_graph_slot(true);
    auto& slot = outbox_->graph(event.graph_slot);
    slot.keyframe_id = open->keyframe_id;
    slot.graph = *open->graph;  // within capacity: no allocation
    outbox_->push(event, true);
  }
  shared_.ring.release_previous();
}

// Odometry starts again from the next frame in a new session (the publisher notes it when that
// session's first pose goes out: this thread does not allocate).
void Tracking::start_new_session() {
  end_session();
  keyframe_covariances_.clear();
  session_frames_ = 0;
  shared_.session = new_session_id(static_cast<std::uint64_t>(shared_.session.load()));
}

void Tracking::count_allocations() {
  const auto warmup = static_cast<std::int64_t>(shared_.config.trackerd.warmup_frames);
  if (++warm_frames_ == warmup) allocations_at_warmup_ = thread_allocations();
  if (warm_frames_ > warmup)
    shared_.counters.allocations_after_warmup = defects_before_ + thread_allocations() - allocations_at_warmup_;
}

}  // namespace cvo::daemon::trackerd
