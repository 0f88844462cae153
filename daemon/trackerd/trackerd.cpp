#include "daemon/trackerd/trackerd.hpp"

#include <poll.h>
#include <signal.h>
#include <sys/random.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <iostream>
#include <optional>
#include <span>
#include <utility>

#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/keyframe_request_t.hpp"
#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/local_graph_t.hpp"
#include "cvo_lcm/map_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "program/allocation_counter.hpp"
#include "daemon/common/latency_window.hpp"
#include "daemon/common/realtime.hpp"
#include "daemon/common/signals.hpp"
#include "daemon/trackerd/keyframe_history.hpp"
#include "drivers/reconnecting_source.hpp"
#include "libcvo/config/module_parameters.hpp"
#include "libcvo/core/units.hpp"
#include "libcvo/io/intrinsics_file.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/lcm/local_graph_conversion.hpp"
#include "libcvo/lcm/map_conversion.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"
#include "libcvo/odometry/keyframe_output.hpp"

namespace cvo::daemon::trackerd {
namespace {

using program::thread_allocations;

using namespace std::chrono_literals;

constexpr const char* kProcess = "cvo-trackerd";
constexpr std::size_t kOutboxEvents = 64;  // 2 s at 30 Hz: the publisher may stall that long
constexpr std::size_t kPoolSlots = 8;      // keyframes / local graphs in flight to the publisher

// 64 random bits from the kernel: unique across restarts and machines. getrandom(2) neither
// allocates nor blocks once the kernel's pool is ready (it was for the first session), so the
// tracking thread may call it. 0 means "no session" (status_t), so it is never an id. Should the
// call fail, the clock mixed into the previous id (splitmix64) still gives a new one.
std::int64_t new_session_id(std::uint64_t previous = 0) {
  std::uint64_t id = 0;
  while (id == 0) {
    const auto n = getrandom(&id, sizeof id, 0);
    if (n == static_cast<ssize_t>(sizeof id) || (n < 0 && errno == EINTR)) continue;
    std::uint64_t z = previous += 0x9e3779b97f4a7c15ULL + static_cast<std::uint64_t>(core::steady_now_ns());
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    id = z ^ (z >> 31);
  }
  return static_cast<std::int64_t>(id);
}


bool is_device(const std::string& spec) { return spec.starts_with("openni2:") || spec.starts_with("v4l2:"); }

// Intrinsics for the sources that carry none (v4l2): the configured camera, and its depth sensor
// when depth is separate (a bad camera file throws here, at start-up, not in a thread). The others bring their own (TUM folder, CVO_RGBD
// message, OpenNI2 stream).
drivers::SourceOptions source_options(const config::Config& config) {
  drivers::SourceOptions options;
  options.realtime = config.trackerd.paced;
  if (config.trackerd.source.starts_with("v4l2:")) {
    const io::CameraFile camera = io::load_camera_file(config.camera);
    options.intrinsics = camera.colour;
    options.depth_sensor = camera.depth_sensor;
  }
  return options;
}

// The source trackerd.source names; devices are re-opened with back-off when they go away.
Trackerd::SourceFactory configured_source(const config::Config& config) {
  return [spec = config.trackerd.source, options = source_options(config)]() -> std::unique_ptr<drivers::FrameSource> {
    if (is_device(spec)) return std::make_unique<drivers::ReconnectingSource>(spec, options);
    return drivers::open_source(spec, options);
  };
}

// Covariance of a frame's pose relative to its keyframe: the inverse CVO Hessian of the keyframe
// registration (the last keyframe->frame edge), when the frame has one.
std::optional<core::Matrix6d> keyframe_covariance(const odometry::KeyframeOdometry& tracker, std::uint64_t frame) {
  const auto& edges = tracker.current_local_graph().edges();
  for (auto it = edges.rbegin(); it != edges.rend() && it != edges.rbegin() + 2; ++it)
    if (it->to == frame && it->from == tracker.keyframe_index()) {
      const Eigen::FullPivLU<core::Matrix6d> lu(it->information);
      if (lu.isInvertible()) return lu.inverse();
    }
  return std::nullopt;
}

// Room for the largest CVO_KEYFRAME a pipeline can publish: every point, the images raw plus an
// eighth for the encoders' own overhead (a compressed image larger than that is pathological, and
// not kept); and for a full local graph (a node and two edges per frame).
std::size_t max_keyframe_bytes(int width, int height, const odometry::KeyframeOdometryParameters& parameters) {
  const auto pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  const std::size_t images = pixels * (3 + 2);  // BGR8 and 16-bit depth
  return static_cast<std::size_t>(cvo_lcm::keyframe_t{}.getEncodedSize()) + parameters.odometry.max_points * (3 + 5) * sizeof(float) +
         images + images / 8;
}

std::size_t max_local_graph_bytes(const odometry::KeyframeOdometryParameters& parameters) {
  cvo_lcm::local_graph_t graph{};
  const auto empty = static_cast<std::size_t>(graph.getEncodedSize());
  graph.num_nodes = 1;
  graph.nodes.resize(1);
  const auto node = static_cast<std::size_t>(graph.getEncodedSize()) - empty;
  graph.num_edges = 1;
  graph.edges.resize(1);
  const auto edge = static_cast<std::size_t>(graph.getEncodedSize()) - empty - node;
  return empty + parameters.tracking.local_graph_capacity * (node + 2 * edge);
}

// Frames of the same camera: every intrinsic, the size included. A camera change needs a new
// session (its poses are in another odometry), and a new size a new pipeline.
bool same_camera(const core::Intrinsics& a, const core::Intrinsics& b) {
  return a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy && a.width == b.width && a.height == b.height &&
         a.depth_scale == b.depth_scale && a.distortion == b.distortion;
}

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

std::string id_list(const std::vector<std::int64_t>& ids) {
  std::string out;
  for (const auto id : ids) out += (out.empty() ? "" : ", ") + std::to_string(id);
  return out;
}

}  // namespace

// What only the tracking thread uses, sized by its camera: made again when the camera changes size.
struct Tracking {
  Tracking(const core::Intrinsics& k, const odometry::KeyframeOdometryParameters& parameters)
      : camera(k), tracker(k.width, k.height, parameters), output(k.width, k.height) {}
  core::Intrinsics camera;  // of the frames it tracks
  odometry::KeyframeOdometry tracker;
  odometry::KeyframeOutput output;  // which frame each keyframe is, and its id in the session
};

// Everything sized by the camera. Owned by Trackerd; the tracking thread uses `tracking`, both
// threads the outbox (thread-safe), the publisher the history.
struct Trackerd::Pipeline {
  Pipeline(const core::Intrinsics& k, const odometry::KeyframeOdometryParameters& p, std::size_t history_keyframes)
      : parameters(p),
        tracking(std::make_unique<Tracking>(k, p)),
        outbox(kOutboxEvents, kPoolSlots, k.width, k.height, p.odometry.max_points, p.tracking.local_graph_capacity),
        history(history_keyframes, max_keyframe_bytes(k.width, k.height, p), max_local_graph_bytes(p)) {}
  const odometry::KeyframeOdometryParameters parameters;
  std::unique_ptr<Tracking> tracking;
  Outbox outbox;
  KeyframeHistory history;  // what was published, for CVO_KEYFRAME_REQUEST
  std::int64_t session_frames = 0;  // frames tracked in the running session
  std::uint64_t connection = 0;     // the source connection they came from (RingSlot::connection)
  std::uint64_t first_index = 0;    // acquisition's index of the session's first frame (0 after a reconnection)
  core::Intrinsics other_camera;    // another camera's frames, in a row: other_frames of them
  std::size_t other_frames = 0;
  // Warm-up, again after a camera change: allocations are defects from warmup_frames frames on.
  std::int64_t warm_frames = 0, allocations_at_warmup = 0, defects_before = 0;
};

Trackerd::Trackerd(config::Config config) : Trackerd(std::move(config), SourceFactory{}) {}

Trackerd::Trackerd(config::Config config, SourceFactory open_source)
    : config_(std::move(config)), open_source_(std::move(open_source)), session_(new_session_id()) {
  const auto& t = config_.trackerd;
  if (t.source.find(':') == std::string::npos)
    throw io::InputError("trackerd.source", "'" + t.source + "': expected tum:DIR, lcm:URL, openni2:URI or v4l2:DEV");
  if (!lcm::parse_colour_encoding(t.keyframe_colour_encoding))
    throw io::InputError("trackerd.keyframe_colour_encoding", "'" + t.keyframe_colour_encoding + "': expected raw, jpeg or png");
  if (!open_source_) open_source_ = configured_source(config_);
  ring_ = std::make_unique<FrameRing>(t.ring_slots, t.deterministic ? FrameRing::Overflow::kBlock
                                                                    : FrameRing::Overflow::kDropOldest);
  ::lcm::LCM probe(t.lcm_url);  // the publisher opens its own; a bad URL should fail at start-up
  if (!probe.good()) throw io::InputError("trackerd.lcm_url", "cannot open LCM provider '" + t.lcm_url + "'");
}

Trackerd::~Trackerd() = default;

void Trackerd::note(const std::string& detail) {
  std::cerr << kProcess << ": " << detail << std::endl;
  const std::lock_guard lock(detail_mutex_);
  detail_ = detail;
}

void Trackerd::count_bad(int kind, const std::string& what, const std::string& why) {
  if (kind < 0 || kind >= cvo_lcm::status_t::NUM_BAD_KINDS) kind = cvo_lcm::status_t::BAD_CONTENT;
  const auto n = ++counters_.bad_messages[kind];
  if (n <= 10 || (n & (n - 1)) == 0) note(what + " #" + std::to_string(n) + ": " + why);
}

int Trackerd::run() {
  const auto& t = config_.trackerd;
  note("session " + slam::session_name(session_));
  note("source " + t.source + ", publishing on " + t.lcm_url + (t.deterministic ? " (deterministic)" : ""));
  if (t.lock_memory)
    if (const auto why = lock_all_memory(); !why.empty()) note("warning: " + why + "; running without locked memory");

  std::thread acquire([this] { acquire_loop(); });
  std::thread track([this] { track_loop(); });
  std::thread publish([this] { publish_loop(); });
  systemd_.ready();

  auto last_watchdog = Clock::now();
  const auto alive = [&](const std::atomic<std::int64_t>& heartbeat) {
    return core::steady_now_ns() - heartbeat.load() < std::chrono::nanoseconds(5s).count();
  };
  while (!publisher_done_) {
    if (const auto signal = wait_for_stop_signal(50ms)) {
      note(std::string("stopping on ") + (*signal == SIGTERM ? "SIGTERM" : "SIGINT"));
      break;
    }
    if (tracker_done_ && !stop_) break;  // the source ended (exit-on-eof) or could not be opened
    if (const auto period = systemd_.watchdog_period(); period && Clock::now() - last_watchdog >= *period) {
      // Only while both workers make progress: a hung tracker should be restarted by systemd.
      if (alive(track_heartbeat_ns_) && alive(publish_heartbeat_ns_)) systemd_.watchdog();
      last_watchdog = Clock::now();
    }
  }
  systemd_.stopping();
  stop_ = true;
  ring_->close();
  acquire.join();
  track.join();
  publish.join();
  const auto dropped = ring_->dropped();
  note("tracked " + std::to_string(counters_.frames_tracked.load()) + " frames: " +
       std::to_string(counters_.keyframes.load()) + " keyframes, " + std::to_string(counters_.failed_frames.load()) +
       " failed, " + std::to_string(dropped) + " dropped by the ring, " +
       std::to_string(counters_.source_lost_frames.load()) + " missing from the source; tracking-thread allocations after warm-up: " +
       std::to_string(counters_.allocations_after_warmup.load()));
  return fatal_ ? 1 : 0;
}

// ---------------------------------------------------------------------------------------------
// cvo-acquire

void Trackerd::acquire_loop() {
  name_this_thread("cvo-acquire");
  const auto& t = config_.trackerd;
  std::unique_ptr<drivers::FrameSource> source;
  try {
    source = open_source_();
  } catch (const std::exception& e) {
    note(std::string("cannot open the frame source: ") + e.what());
    fatal_ = true;  // a folder or URL that is wrong now stays wrong; devices are retried above
    ring_->close();
    return;
  }
  note("reading " + source->describe());
  counters_.source_connected = true;

  // Frame indices of the session: increasing for the tracker, from 0 again when the source comes
  // back after a disconnection (a new connection, and so a new session).
  std::int64_t next_index = 0;
  std::uint64_t connection = 0;
  bool connected = true;
  while (!stop_) {
    RingSlot* slot = ring_->begin_write();
    if (slot == nullptr) break;  // closed
    const auto result = source->read(slot->frame, 100ms);
    counters_.source_lost_frames = static_cast<std::int64_t>(source->lost_frames());
    switch (result.status) {
      case drivers::ReadStatus::kFrame:
        if (!connected) {
          connected = true;
          ++connection;
          next_index = 0;
          counters_.source_connected = true;
          note("frames again from " + source->describe());
        }
        slot->received = Clock::now();
        slot->frame.index = static_cast<std::uint64_t>(next_index++);
        slot->connection = connection;
        ring_->commit_write();
        continue;
      case drivers::ReadStatus::kTimeout: break;
      case drivers::ReadStatus::kBadInput:
        count_bad(static_cast<int>(result.bad_input), "skipped bad input", result.message);
        break;
      case drivers::ReadStatus::kDisconnected:
        if (connected) {
          connected = false;
          counters_.source_connected = false;
          ++counters_.source_gaps;
          note("source lost: " + result.message + "; re-opening with back-off");
        }
        break;
      case drivers::ReadStatus::kEndOfStream:
        ring_->abort_write();
        note("end of " + source->describe());
        if (t.exit_on_eof) {
          ring_->close();
          return;
        }
        while (!stop_) std::this_thread::sleep_for(50ms);  // stay up, reporting, until stopped
        return;
    }
    ring_->abort_write();
  }
}

// ---------------------------------------------------------------------------------------------
// cvo-track

void Trackerd::track_loop() {
  name_this_thread("cvo-track");
  const auto& t = config_.trackerd;
  track_heartbeat_ns_ = core::steady_now_ns();
  if (t.realtime_priority > 0)
    if (const auto why = make_this_thread_realtime(t.realtime_priority); !why.empty())
      note("warning: " + why + "; tracking at normal priority");
  if (t.cpu >= 0)
    if (const auto why = pin_this_thread(t.cpu); !why.empty()) note("warning: " + why);

  Pipeline* p = nullptr;
  while (true) {
    track_heartbeat_ns_ = core::steady_now_ns();
    RingSlot* slot = ring_->begin_read(100ms);
    if (slot == nullptr) {
      if (ring_->drained()) break;
      continue;
    }
    if (p == nullptr) p = start_pipeline(slot->frame);
    if (p != nullptr && slot->connection != p->connection) {
      if (p->session_frames > 0) start_new_session(*p);
      p->connection = slot->connection;
      p->first_index = 0;  // acquisition counts from 0 again
    }
    if (p == nullptr || !accept_camera(*p, slot->frame)) {  // counted, without a note: no allocation here
      ++counters_.bad_messages[cvo_lcm::status_t::BAD_CONTENT];
      ring_->end_read();
      continue;
    }
    slot->frame.index -= p->first_index;  // frame indices count from 0 in a session

    Event event;
    track_frame(*p, *slot, event);
    ring_->end_read();
    p->outbox.push(event, t.deterministic);  // when full, dropped: counted, with what it carried
    ++p->session_frames;
    ++counters_.frames_tracked;
    if (++p->warm_frames == static_cast<std::int64_t>(t.warmup_frames)) p->allocations_at_warmup = thread_allocations();
    if (p->warm_frames > static_cast<std::int64_t>(t.warmup_frames))
      counters_.allocations_after_warmup = p->defects_before + thread_allocations() - p->allocations_at_warmup;
  }
  if (p != nullptr) {
    publish_open_graph(*p);  // the end of the session: the back end gets every tracked frame
    p->outbox.close();
  }
  tracker_done_ = true;
}

// The pipeline for frames of this one's camera, or nullptr (counted) when it cannot be tracked.
Trackerd::Pipeline* Trackerd::start_pipeline(const core::RgbdFrame& first) {
  if (!usable(first)) return nullptr;
  pipeline_ = std::make_unique<Pipeline>(first.intrinsics, config::keyframe_odometry_parameters(config_),
                                         config_.trackerd.keyframe_history);
  camera_size_ = packed_size(first.intrinsics.width, first.intrinsics.height);
  pipeline_ready_ = true;
  return pipeline_.get();
}

// Whether `frame` may be tracked: it comes from the pipeline's camera, or from another camera whose
// frames have now come trackerd.camera_change_frames times in a row, and the tracker re-initialises
// for it. A lone frame of another camera is refused and does not disturb tracking.
bool Trackerd::accept_camera(Pipeline& p, const core::RgbdFrame& frame) {
  if (same_camera(frame.intrinsics, p.tracking->camera)) {  // validated when the pipeline was made
    if (!images_fit(frame)) return false;
    p.other_frames = 0;
    return true;
  }
  if (!usable(frame)) return false;
  if (p.other_frames == 0 || !same_camera(frame.intrinsics, p.other_camera)) {
    p.other_camera = frame.intrinsics;
    p.other_frames = 0;
  }
  if (++p.other_frames < config_.trackerd.camera_change_frames) return false;
  change_camera(p, frame);
  return true;
}

// Another camera (a new size or new intrinsics) for good: its frames start a new session from
// `first`; a new size needs a tracker and keyframe slots of that size. That allocation is the
// camera change's, reported once here, and warm-up starts again before allocations count as defects.
void Trackerd::change_camera(Pipeline& p, const core::RgbdFrame& first) {
  const core::Intrinsics& k = first.intrinsics;
  const std::int64_t allocations_before = thread_allocations();
  const std::string from = size_name(p.tracking->camera);
  if (p.session_frames > 0) start_new_session(p);  // the old session's open local graph goes out first
  const bool resized = k.width != p.tracking->camera.width || k.height != p.tracking->camera.height;
  if (resized) {
    p.tracking.reset();  // before the new one: never both in memory
    p.tracking = std::make_unique<Tracking>(k, p.parameters);
    p.outbox.resize_keyframe_images(k.width, k.height);
    camera_size_ = packed_size(k.width, k.height);
  } else {
    p.tracking->camera = k;
  }
  p.first_index = first.index;
  p.other_frames = 0;
  p.defects_before = counters_.allocations_after_warmup;
  p.warm_frames = 0;
  note("camera changed (" + from + " to " + size_name(k) + ", fx " + std::to_string(k.fx) + ") for " +
       std::to_string(config_.trackerd.camera_change_frames) + " frames in a row: tracking again in session " +
       slam::session_name(session_.load()) +
       (resized ? "; the pipeline for the new size took " + std::to_string(thread_allocations() - allocations_before) +
                      " allocations (not counted as realtime defects: warm-up again)"
                : ""));
}

// One frame through KF-CVO into an event: its pose (map pose when CVO_MAP places the session), the
// local graph it closed and the keyframe it made, copied into preallocated outbox slots.
void Trackerd::track_frame(Pipeline& p, const RingSlot& slot, Event& event) {
  const core::RgbdFrame& frame = slot.frame;
  odometry::KeyframeOdometry& tracker = p.tracking->tracker;
  odometry::KeyframeOutput& output = p.tracking->output;
  const odometry::TrackResult result = tracker.track(frame);
  const odometry::KeyframeStep step = output.after_track(tracker, result, frame);
  const bool wait = config_.trackerd.deterministic;  // never lose a graph or keyframe in a replay
  event.session = session_.load(std::memory_order_relaxed);

  PoseEvent& e = event.pose;
  const MapPlacement placement = correction_.get(event.session);
  e.frame_index = static_cast<std::int64_t>(frame.index);
  e.timestamp = frame.timestamp;
  e.received = slot.received;
  e.status = result.status;
  e.odom_pose = result.pose;
  e.map_pose = placement.T_map_odom * result.pose;
  e.map_placed = placement.placed;
  e.inner_product = result.inner_product;
  e.gamma_keyframe = tracker.gamma();
  e.iterations = result.iterations;
  e.points = static_cast<int>(result.points);
  e.keyframe_id = output.keyframe_id();
  e.is_keyframe = result.keyframe;
  if (const auto covariance = keyframe_covariance(tracker, frame.index)) e.covariance = *covariance;
  if (!result.tracked()) ++counters_.failed_frames;

  // A graph or keyframe that finds no slot (the publisher is behind) is counted lost by the outbox.
  if (step.closed_graph != nullptr && (event.graph_slot = p.outbox.acquire_graph_slot(wait)) >= 0) {
    auto& g = p.outbox.graph(event.graph_slot);
    g.keyframe_id = step.closed_graph_keyframe;
    g.graph = *step.closed_graph;  // within capacity: no allocation
  }
  if (step.keyframe_id >= 0) ++counters_.keyframes;
  if (step.keyframe != nullptr && (event.keyframe_slot = p.outbox.acquire_keyframe_slot(wait)) >= 0) {
    auto& k = p.outbox.keyframe(event.keyframe_slot);
    const core::RgbdFrame& source = *step.keyframe;
    k.id = step.keyframe_id;
    k.pose = step.keyframe_pose;
    k.frame.index = source.index;
    k.frame.timestamp = source.timestamp;
    k.frame.depth_timestamp = source.depth_timestamp;
    k.frame.intrinsics = source.intrinsics;
    source.bgr.copyTo(k.frame.bgr);  // same-sized images: no allocation
    source.depth.copyTo(k.frame.depth);
    k.cloud = tracker.keyframe_cloud();  // same capacity: copies points, no allocation
  }
  output.keep(frame);
}

// The open local graph of the running session (its current keyframe and the frames tracked
// against it), as the tracker stops or the session ends. Waiting for room is harmless here: the
// source has ended or was away.
void Trackerd::publish_open_graph(Pipeline& p) {
  const auto& open = p.tracking->tracker.current_local_graph();
  if (open.empty() || p.tracking->output.keyframe_id() < 0) return;
  Event event;
  event.session = session_.load(std::memory_order_relaxed);
  event.has_pose = false;
  event.graph_slot = p.outbox.acquire_graph_slot(true);
  auto& g = p.outbox.graph(event.graph_slot);
  g.keyframe_id = p.tracking->output.keyframe_id();
  g.graph = open;  // within capacity: no allocation
  p.outbox.push(event, true);
}

// The source came back: the camera may have been re-initialised, so odometry starts again from
// its first frame in a new session (the publisher notes it when that session's first pose goes
// out: this thread does not allocate).
void Trackerd::start_new_session(Pipeline& p) {
  publish_open_graph(p);
  p.tracking->tracker.reset();
  p.tracking->output.reset();
  p.session_frames = 0;
  session_ = new_session_id(static_cast<std::uint64_t>(session_.load()));
}

// ---------------------------------------------------------------------------------------------
// cvo-publish

// What the publisher thread keeps between events and status messages.
struct Trackerd::Publisher {
  explicit Publisher(const config::TrackerdParameters& t, std::int64_t first_session)
      : lcm(t.lcm_url),
        encoding{*lcm::parse_colour_encoding(t.keyframe_colour_encoding), lcm::DepthEncoding::kPng},
        session(first_session) {}
  ::lcm::LCM lcm;
  LatencyWindow latency{1024};
  lcm::RgbdEncoding encoding;
  std::int64_t session;  // of the last event published
  std::int64_t published = 0, published_at_last_status = 0, deadline_misses = 0, failed_at_last_status = 0;
  std::int64_t unsent = 0;               // keyframes that could not be encoded (lost before publication)
  std::int64_t outbox_lost_noted = 0;    // the outbox's lost() when last noted
  std::int64_t requests_answered = 0;
  Clock::time_point last_status = Clock::now(), last_frame = Clock::now();
};

void Trackerd::publish_loop() {
  name_this_thread("cvo-publish");
  const auto& t = config_.trackerd;
  Publisher out(t, session_.load());
  publish_heartbeat_ns_ = core::steady_now_ns();

  struct MapHandler {
    Trackerd* self;
    void handle(const ::lcm::ReceiveBuffer* buffer, const std::string& /*channel*/) {
      self->apply_map(buffer->data, static_cast<int>(buffer->data_size));
    }
  } map_handler{this};
  struct RequestHandler {
    Trackerd* self;
    Publisher* out;
    void handle(const ::lcm::ReceiveBuffer* buffer, const std::string& /*channel*/) {
      self->answer_request(*out, buffer->data, static_cast<int>(buffer->data_size));
    }
  } request_handler{this, &out};
  // A file:// output is a log being written: nothing comes back on it.
  const bool receives = !t.lcm_url.starts_with("file://");
  if (receives) {
    out.lcm.subscribe("CVO_MAP", &MapHandler::handle, &map_handler);
    out.lcm.subscribe("CVO_KEYFRAME_REQUEST", &RequestHandler::handle, &request_handler);
  }

  const int fd = receives ? out.lcm.getFileno() : -1;
  Event event;
  while (true) {
    publish_heartbeat_ns_ = core::steady_now_ns();
    if (pipeline_ready_) {
      if (pipeline_->outbox.pop(event, 10ms)) publish_event(out, event);
      else if (tracker_done_ && pipeline_->outbox.finished()) break;
    } else if (tracker_done_) {
      break;
    } else {
      std::this_thread::sleep_for(10ms);
    }
    if (fd >= 0) {  // CVO_MAP and CVO_KEYFRAME_REQUEST, without blocking the poses
      pollfd pfd{fd, POLLIN, 0};
      while (poll(&pfd, 1, 0) > 0 && (pfd.revents & POLLIN) != 0) out.lcm.handle();
    }
    if (Clock::now() - out.last_status >= std::chrono::duration<double>(t.status_period_s)) publish_status(out, -1);
  }
  publish_status(out, cvo_lcm::status_t::STATE_STOPPING);
  publisher_done_ = true;
}

void Trackerd::publish_event(Publisher& out, const Event& event) {
  Pipeline& p = *pipeline_;
  if (event.session != out.session) {  // noted here: the tracking thread does not allocate
    out.session = event.session;
    note("camera re-initialised: new session " + slam::session_name(event.session));
    const std::uint64_t size = camera_size_.load();  // a camera change may have made keyframes larger
    p.history.reserve_keyframe_bytes(max_keyframe_bytes(static_cast<int>(size >> 32),
                                                        static_cast<int>(size & 0xffffffffU), p.parameters));
  }
  if (event.has_pose && event.pose.keyframe_id >= 0) p.history.made(event.session, event.pose.keyframe_id);
  if (event.graph_slot >= 0) {  // encoded here, so that the history keeps the very bytes sent
    const auto& g = p.outbox.graph(event.graph_slot);
    const auto bytes = lcm::encode(lcm::to_message(g.graph, event.session, g.keyframe_id, core::wall_utime()));
    out.lcm.publish("CVO_LOCAL_GRAPH", bytes.data(), static_cast<unsigned>(bytes.size()));
    p.history.keep_graph(event.session, g.keyframe_id, bytes);
  }
  if (event.keyframe_slot >= 0) publish_keyframe(out, event);
  else if (event.has_pose && event.pose.is_keyframe)  // no outbox slot: counted by the outbox
    p.history.never_sent(event.session, event.pose.keyframe_id);
  if (event.has_pose) {
    const double latency_ms = core::ms_since(event.pose.received);
    const cvo_lcm::pose_t m = lcm::pose_message(event.session, event.pose, latency_ms);
    out.lcm.publish("CVO_POSE", &m);
    out.latency.add(m.latency_ms);
    if (m.latency_ms > config_.trackerd.deadline_ms) ++out.deadline_misses;
    if (out.published++ == 0) note("first pose published");
    out.last_frame = Clock::now();
  }
  p.outbox.release(event);
}

void Trackerd::publish_keyframe(Publisher& out, const Event& event) {
  Pipeline& p = *pipeline_;
  const auto& k = p.outbox.keyframe(event.keyframe_slot);
  std::string error;
  const lcm::Keyframe keyframe{event.session, k.id, k.frame, k.pose, k.cloud};
  const auto message = lcm::to_message(keyframe, out.encoding, &error);
  if (!message) {
    ++out.unsent;
    p.history.never_sent(event.session, k.id);
    note("keyframe " + std::to_string(k.id) + " not published (lost): " + error);
    return;
  }
  const auto bytes = lcm::encode(*message);
  out.lcm.publish("CVO_KEYFRAME", bytes.data(), static_cast<unsigned>(bytes.size()));
  if (!p.history.keep_keyframe(event.session, k.id, bytes) && p.history.capacity() > 0)
    note("keyframe " + std::to_string(k.id) + " (" + std::to_string(bytes.size()) +
         " bytes) is larger than a history slot: it cannot be sent again");
}

// CVO_KEYFRAME_REQUEST: the back end missed keyframes of a session; those of this tracker's sessions
// that the history still holds go out again as first sent (keyframe, then its local graph).
// Requests for other sessions are other trackers'.
void Trackerd::answer_request(Publisher& out, const void* data, int size) {
  std::string error;
  auto failure = lcm::DecodeFailure::kBody;
  const auto request = lcm::decode<cvo_lcm::keyframe_request_t>(data, size, &error, &failure);
  if (!request) return count_bad(static_cast<int>(failure), "skipped CVO_KEYFRAME_REQUEST", error);
  const std::string what = "CVO_KEYFRAME_REQUEST for session " + slam::session_name(request->session);
  if (request->num_ids > cvo_lcm::keyframe_request_t::MAX_IDS)
    return count_bad(cvo_lcm::status_t::BAD_CONTENT, "skipped " + what,
                     std::to_string(request->num_ids) + " ids, more than " +
                         std::to_string(cvo_lcm::keyframe_request_t::MAX_IDS));
  if (!pipeline_ready_) {  // nothing made yet: only a request for the running session concerns us
    if (request->session == session_.load()) count_bad(cvo_lcm::status_t::BAD_CONTENT, "skipped " + what, "no keyframe made yet");
    return;
  }
  const auto send = [&](const char* channel, std::span<const std::uint8_t> bytes) {
    out.lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  };
  const auto answer = pipeline_->history.answer(request->session, request->ids, send);
  if (!answer.ours) return;
  if (!answer.never.empty())
    count_bad(cvo_lcm::status_t::BAD_CONTENT, "skipped part of " + what, "keyframes " + id_list(answer.never) + " were never made");
  if (answer.sent.empty() && answer.lost.empty()) return;
  const auto n = ++out.requests_answered;
  if (n > 10 && (n & (n - 1)) != 0) return;  // the first ones, then fewer: a lossy link must not flood the log
  std::string done = answer.sent.empty() ? "" : "sent " + id_list(answer.sent);
  if (!answer.lost.empty())
    done += (done.empty() ? "" : "; ") + std::string("lost (not in the history of ") +
            std::to_string(pipeline_->history.capacity()) + "): " + id_list(answer.lost);
  note("the back end asked again for keyframes of session " + slam::session_name(request->session) + " (#" +
       std::to_string(n) + "): " + done);
}

void Trackerd::publish_status(Publisher& out, std::int8_t state_override) {
  const auto now = Clock::now();
  const double elapsed = std::chrono::duration<double>(now - out.last_status).count();
  lcm::ProcessStatus s;
  s.process = kProcess;
  s.session = out.session;
  s.utime = core::wall_utime();
  s.pid = static_cast<std::int32_t>(getpid());
  s.rate_hz = elapsed > 0 ? static_cast<double>(out.published - out.published_at_last_status) / elapsed : 0;
  const auto l = out.latency.summary();
  s.latency_median_ms = l.median_ms;
  s.latency_p99_ms = l.p99_ms;
  s.deadline_misses = out.deadline_misses;
  s.dropped_frames = ring_->dropped() + counters_.source_lost_frames;
  s.failed_frames = counters_.failed_frames;
  s.source_gaps = counters_.source_gaps;
  s.allocations_after_warmup = counters_.allocations_after_warmup;
  s.queue_depth = static_cast<std::int32_t>(ring_->waiting());
  s.rss_bytes = resident_bytes();
  for (std::size_t k = 0; k < s.bad_messages.size(); ++k) s.bad_messages[k] = counters_.bad_messages[k];
  const std::int64_t outbox_lost = pipeline_ready_ ? pipeline_->outbox.lost() : 0;
  if (outbox_lost > out.outbox_lost_noted) {  // noted here: the tracking thread does not allocate
    note(std::to_string(outbox_lost) + " keyframes or local graphs lost before publication (the publisher fell behind)");
    out.outbox_lost_noted = outbox_lost;
  }
  s.keyframes_requested = pipeline_ready_ ? pipeline_->history.resent() : 0;
  s.keyframes_lost = outbox_lost + out.unsent + (pipeline_ready_ ? pipeline_->history.lost() : 0);
  {
    const std::lock_guard lock(detail_mutex_);
    s.detail = detail_;
  }
  s.state = state_override >= 0 ? state_override
                                : lcm::tracker_state({out.published, counters_.source_connected.load(),
                                                      now - out.last_frame > 1s,
                                                      counters_.failed_frames > out.failed_at_last_status});
  const cvo_lcm::status_t message = lcm::status_message(s);
  out.lcm.publish("CVO_STATUS", &message);
  systemd_.status(std::to_string(out.published) + " frames, " + std::to_string(static_cast<int>(std::lround(s.rate_hz))) +
                  " Hz, latency p99 " + std::to_string(static_cast<int>(std::lround(s.latency_p99_ms))) + " ms, " +
                  std::to_string(s.dropped_frames) + " dropped");
  out.published_at_last_status = out.published;
  out.failed_at_last_status = counters_.failed_frames;
  out.last_status = now;
}

// CVO_MAP: what lcm::decide_map_correction trusts moves the running session's map poses (placed:
// its correction; not placed: map pose = odometry pose); anything else is counted by kind.
void Trackerd::apply_map(const void* data, int size) {
  const std::int64_t session = session_.load();
  const auto& t = config_.trackerd;
  const lcm::CorrectionDecision d =
      lcm::decide_map_correction(data, size, session, applied_, {t.max_map_jump_m, t.max_map_jump_deg});
  if (!d.apply) return count_bad(static_cast<int>(d.refusal), "skipped CVO_MAP", d.why);
  const bool was_placed = applied_.session == session && applied_.placed;
  if (d.correction.placed != was_placed)
    note("session " + slam::session_name(session) + (d.correction.placed ? " placed in the map" : " no longer placed in the map") +
         " (map revision " + std::to_string(d.correction.revision) + ")");
  applied_ = d.correction;
  correction_.set(session, {d.correction.T_map_odom, d.correction.placed});
}

}  // namespace cvo::daemon::trackerd
