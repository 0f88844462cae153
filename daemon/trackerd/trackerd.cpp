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
#include "daemon/common/allocation_counter.hpp"
#include "daemon/common/latency_window.hpp"
#include "daemon/common/realtime.hpp"
#include "daemon/common/signals.hpp"
#include "daemon/trackerd/keyframe_history.hpp"
#include "drivers/reconnecting_source.hpp"
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

using namespace std::chrono_literals;

constexpr const char* kProcess = "cvo-trackerd";
constexpr std::size_t kOutboxEvents = 64;  // 2 s at 30 Hz: the publisher may stall that long
constexpr std::size_t kPoolSlots = 8;      // keyframes / local graphs in flight to the publisher

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

std::int64_t wall_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// 64 random bits from the kernel: unique across restarts and machines. getrandom(2) neither
// allocates nor blocks once the kernel's pool is ready (it was for the first session), so the
// tracking thread may call it. 0 means "no session" (status_t), so it is never an id. Should the
// call fail, the clock mixed into the previous id (splitmix64) still gives a new one.
std::int64_t new_session_id(std::uint64_t previous = 0) {
  std::uint64_t id = 0;
  while (id == 0) {
    const auto n = getrandom(&id, sizeof id, 0);
    if (n == static_cast<ssize_t>(sizeof id) || (n < 0 && errno == EINTR)) continue;
    std::uint64_t z = previous += 0x9e3779b97f4a7c15ULL + static_cast<std::uint64_t>(now_ns());
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    id = z ^ (z >> 31);
  }
  return static_cast<std::int64_t>(id);
}


std::int8_t to_pose_status(odometry::TrackStatus status) {
  switch (status) {
    case odometry::TrackStatus::kOk: return cvo_lcm::pose_t::STATUS_OK;
    case odometry::TrackStatus::kFirstFrame: return cvo_lcm::pose_t::STATUS_FIRST_FRAME;
    case odometry::TrackStatus::kSelectionFailed: return cvo_lcm::pose_t::STATUS_SELECTION_FAILED;
    case odometry::TrackStatus::kRegistrationFailed: return cvo_lcm::pose_t::STATUS_REGISTRATION_FAILED;
  }
  return cvo_lcm::pose_t::STATUS_LOST;
}

bool is_device(const std::string& spec) { return spec.starts_with("openni2:") || spec.starts_with("v4l2:"); }

// Intrinsics for the sources that carry none (v4l2): the configured camera (a bad camera file
// throws here, at start-up, not in a thread). The others bring their own (TUM folder, CVO_RGBD
// message, OpenNI2 stream).
drivers::SourceOptions source_options(const config::Config& config) {
  drivers::SourceOptions options;
  options.realtime = config.trackerd.paced;
  if (config.trackerd.source.starts_with("v4l2:")) options.intrinsics = io::load_camera(config.camera);
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

cvo_lcm::pose_t pose_message(const Event& event) {
  const PoseEvent& e = event.pose;
  cvo_lcm::pose_t m{};
  m.version = cvo_lcm::pose_t::SCHEMA_VERSION;
  m.session = event.session;
  m.utime = lcm::to_utime(e.timestamp);
  m.frame_index = e.frame_index;
  m.keyframe_id = e.keyframe_id;
  m.odom_pose = lcm::to_message(e.odom_pose);
  m.map_pose = lcm::to_message(e.map_pose);
  m.map_placed = e.map_placed;
  lcm::matrix6_to_message(e.covariance, m.covariance);
  m.status = to_pose_status(e.status);
  m.is_keyframe = e.is_keyframe;
  m.inner_product = e.inner_product;
  m.gamma_frame = 0;
  m.gamma_keyframe = e.gamma_keyframe;
  m.iterations = e.iterations;
  m.points = e.points;
  m.latency_ms = std::chrono::duration<double, std::milli>(Clock::now() - e.received).count();
  return m;
}

// Room for the largest CVO_KEYFRAME a pipeline can publish: every point, the images raw plus an
// eighth for the encoders' own overhead (a compressed image larger than that is pathological, and
// not kept); and for a full local graph (a node and two edges per frame).
std::size_t max_keyframe_bytes(int width, int height, const odometry::KeyframeOdometryParameters& parameters) {
  const auto pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  const std::size_t images = pixels * (3 + 2);  // BGR8 and 16-bit depth
  return static_cast<std::size_t>(cvo_lcm::keyframe_t{}.getEncodedSize()) + parameters.max_points * (3 + 5) * sizeof(float) +
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
  return empty + parameters.local_graph_capacity * (node + 2 * edge);
}

std::string id_list(const std::vector<std::int64_t>& ids) {
  std::string out;
  for (const auto id : ids) out += (out.empty() ? "" : ", ") + std::to_string(id);
  return out;
}

}  // namespace

// Everything sized by the first frame. Owned by Trackerd; the tracking thread uses the tracker
// and the keyframe output, both threads the outbox (thread-safe), the publisher the history.
struct Trackerd::Pipeline {
  Pipeline(int w, int h, const odometry::KeyframeOdometryParameters& parameters, std::size_t history_keyframes)
      : width(w),
        height(h),
        tracker(w, h, parameters),
        output(w, h),
        outbox(kOutboxEvents, kPoolSlots, w, h, parameters.max_points, parameters.local_graph_capacity),
        history(history_keyframes, max_keyframe_bytes(w, h, parameters), max_local_graph_bytes(parameters)) {}
  int width, height;
  odometry::KeyframeOdometry tracker;
  odometry::KeyframeOutput output;  // which frame each keyframe is, and its id in the session
  Outbox outbox;
  KeyframeHistory history;  // what was published, for CVO_KEYFRAME_REQUEST
  std::int64_t session_frames = 0;  // frames tracked in the running session
  std::uint64_t connection = 0;     // the source connection they came from (RingSlot::connection)
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
    return now_ns() - heartbeat.load() < std::chrono::nanoseconds(5s).count();
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
  track_heartbeat_ns_ = now_ns();
  if (t.realtime_priority > 0)
    if (const auto why = make_this_thread_realtime(t.realtime_priority); !why.empty())
      note("warning: " + why + "; tracking at normal priority");
  if (t.cpu >= 0)
    if (const auto why = pin_this_thread(t.cpu); !why.empty()) note("warning: " + why);

  Pipeline* p = nullptr;
  std::int64_t frames = 0, allocations_at_warmup = 0;
  while (true) {
    track_heartbeat_ns_ = now_ns();
    RingSlot* slot = ring_->begin_read(100ms);
    if (slot == nullptr) {
      if (ring_->drained()) break;
      continue;
    }
    const core::RgbdFrame& frame = slot->frame;
    if (p == nullptr) p = start_pipeline(frame);
    if (p == nullptr || frame.bgr.cols != p->width || frame.bgr.rows != p->height || frame.depth.cols != p->width ||
        frame.depth.rows != p->height) {  // the first frame fixed the size; a change is a new camera
      ++counters_.bad_messages[cvo_lcm::status_t::BAD_CONTENT];
      ring_->end_read();
      continue;
    }
    if (slot->connection != p->connection) {
      if (p->session_frames > 0) start_new_session(*p);
      p->connection = slot->connection;
    }

    Event event;
    track_frame(*p, *slot, event);
    ring_->end_read();
    p->outbox.push(event, t.deterministic);  // when full, dropped: counted, with what it carried
    ++p->session_frames;
    ++counters_.frames_tracked;
    if (++frames == static_cast<std::int64_t>(t.warmup_frames)) allocations_at_warmup = thread_allocations();
    if (frames > static_cast<std::int64_t>(t.warmup_frames))
      counters_.allocations_after_warmup = thread_allocations() - allocations_at_warmup;
  }
  if (p != nullptr) {
    publish_open_graph(*p);  // the end of the session: the back end gets every tracked frame
    p->outbox.close();
  }
  tracker_done_ = true;
}

// The pipeline for frames of this one's size, or nullptr (counted) when its intrinsics are unusable.
Trackerd::Pipeline* Trackerd::start_pipeline(const core::RgbdFrame& first) {
  const auto& k = first.intrinsics;
  if (!k.validate().empty() || first.bgr.cols != k.width || first.bgr.rows != k.height) return nullptr;
  pipeline_ = std::make_unique<Pipeline>(k.width, k.height, odometry::keyframe_odometry_parameters(config_),
                                         config_.trackerd.keyframe_history);
  pipeline_ready_ = true;
  return pipeline_.get();
}

// One frame through KF-CVO into an event: its pose (map pose when CVO_MAP places the session), the
// local graph it closed and the keyframe it made, copied into preallocated outbox slots.
void Trackerd::track_frame(Pipeline& p, const RingSlot& slot, Event& event) {
  const core::RgbdFrame& frame = slot.frame;
  const odometry::TrackResult result = p.tracker.track(frame);
  const odometry::KeyframeStep step = p.output.after_track(p.tracker, result, frame);
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
  e.gamma_keyframe = p.tracker.gamma();
  e.iterations = result.iterations;
  e.points = static_cast<int>(result.points);
  e.keyframe_id = p.output.keyframe_id();
  e.is_keyframe = result.keyframe;
  if (const auto covariance = keyframe_covariance(p.tracker, frame.index)) e.covariance = *covariance;
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
    k.cloud = p.tracker.keyframe_cloud();  // same capacity: copies points, no allocation
  }
  p.output.keep(frame);
}

// The open local graph of the running session (its current keyframe and the frames tracked
// against it), as the tracker stops or the session ends. Waiting for room is harmless here: the
// source has ended or was away.
void Trackerd::publish_open_graph(Pipeline& p) {
  const auto& open = p.tracker.current_local_graph();
  if (open.empty() || p.output.keyframe_id() < 0) return;
  Event event;
  event.session = session_.load(std::memory_order_relaxed);
  event.has_pose = false;
  event.graph_slot = p.outbox.acquire_graph_slot(true);
  auto& g = p.outbox.graph(event.graph_slot);
  g.keyframe_id = p.output.keyframe_id();
  g.graph = open;  // within capacity: no allocation
  p.outbox.push(event, true);
}

// The source came back: the camera may have been re-initialised, so odometry starts again from
// its first frame in a new session (the publisher notes it when that session's first pose goes
// out: this thread does not allocate).
void Trackerd::start_new_session(Pipeline& p) {
  publish_open_graph(p);
  p.tracker.reset();
  p.output.reset();
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
  publish_heartbeat_ns_ = now_ns();

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
    publish_heartbeat_ns_ = now_ns();
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
  }
  if (event.has_pose && event.pose.keyframe_id >= 0) p.history.made(event.session, event.pose.keyframe_id);
  if (event.graph_slot >= 0) {  // encoded here, so that the history keeps the very bytes sent
    const auto& g = p.outbox.graph(event.graph_slot);
    const auto bytes = lcm::encode(lcm::to_message(g.graph, event.session, g.keyframe_id, wall_utime()));
    out.lcm.publish("CVO_LOCAL_GRAPH", bytes.data(), static_cast<unsigned>(bytes.size()));
    p.history.keep_graph(event.session, g.keyframe_id, bytes);
  }
  if (event.keyframe_slot >= 0) publish_keyframe(out, event);
  else if (event.has_pose && event.pose.is_keyframe)  // no outbox slot: counted by the outbox
    p.history.never_sent(event.session, event.pose.keyframe_id);
  if (event.has_pose) {
    const cvo_lcm::pose_t m = pose_message(event);
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
  cvo_lcm::status_t s{};
  s.version = cvo_lcm::status_t::SCHEMA_VERSION;
  s.session = out.session;
  s.utime = wall_utime();
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
  for (int k = 0; k < cvo_lcm::status_t::NUM_BAD_KINDS; ++k) s.bad_messages[k] = counters_.bad_messages[k];
  const std::int64_t outbox_lost = pipeline_ready_ ? pipeline_->outbox.lost() : 0;
  if (outbox_lost > out.outbox_lost_noted) {  // noted here: the tracking thread does not allocate
    note(std::to_string(outbox_lost) + " keyframes or local graphs lost before publication (the publisher fell behind)");
    out.outbox_lost_noted = outbox_lost;
  }
  s.keyframes_requested = pipeline_ready_ ? pipeline_->history.resent() : 0;
  s.keyframes_lost = outbox_lost + out.unsent + (pipeline_ready_ ? pipeline_->history.lost() : 0);
  s.process = kProcess;
  {
    const std::lock_guard lock(detail_mutex_);
    s.detail = detail_;
  }
  const bool idle = now - out.last_frame > 1s;
  if (state_override >= 0) s.state = state_override;
  else if (out.published == 0) s.state = counters_.source_connected ? cvo_lcm::status_t::STATE_STARTING : cvo_lcm::status_t::STATE_WAITING_FOR_INPUT;
  else if (!counters_.source_connected || idle) s.state = cvo_lcm::status_t::STATE_WAITING_FOR_INPUT;
  else if (counters_.failed_frames > out.failed_at_last_status) s.state = cvo_lcm::status_t::STATE_DEGRADED;
  else s.state = cvo_lcm::status_t::STATE_RUNNING;
  out.lcm.publish("CVO_STATUS", &s);
  systemd_.status(std::to_string(out.published) + " frames, " + std::to_string(static_cast<int>(std::lround(s.rate_hz))) +
                  " Hz, latency p99 " + std::to_string(static_cast<int>(std::lround(s.latency_p99_ms))) + " ms, " +
                  std::to_string(s.dropped_frames) + " dropped");
  out.published_at_last_status = out.published;
  out.failed_at_last_status = counters_.failed_frames;
  out.last_status = now;
}

// CVO_MAP: only the running session's entry counts. Placed: its correction moves the map poses;
// unplaced or absent: map pose = odometry pose. Anything undecodable is a counted refusal.
void Trackerd::apply_map(const void* data, int size) {
  std::string error;
  auto failure = lcm::DecodeFailure::kBody;
  const auto message = lcm::decode<cvo_lcm::map_t>(data, size, &error, &failure);
  const auto map = message ? lcm::from_message(*message, &error) : std::nullopt;
  if (!map) {
    count_bad(message ? cvo_lcm::status_t::BAD_CONTENT : static_cast<int>(failure), "skipped CVO_MAP", error);
    return;
  }
  const std::int64_t session = session_.load();
  const auto entry = std::find_if(map->sessions.begin(), map->sessions.end(),
                                  [&](const slam::MapSession& s) { return s.session == session; });
  MapPlacement placement;
  if (entry != map->sessions.end() && entry->placed) placement = {entry->correction, true};
  if (placement.placed != correction_.get(session).placed)
    note("session " + slam::session_name(session) + (placement.placed ? " placed in the map" : " no longer placed in the map") +
         " (map revision " + std::to_string(map->revision) + ")");
  correction_.set(session, placement);
}

}  // namespace cvo::daemon::trackerd
