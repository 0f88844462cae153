#include "daemon/trackerd/trackerd.hpp"

#include <poll.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <optional>
#include <utility>

#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/local_graph_t.hpp"
#include "cvo_lcm/map_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "daemon/common/allocation_counter.hpp"
#include "daemon/common/latency_window.hpp"
#include "daemon/common/realtime.hpp"
#include "daemon/common/signals.hpp"
#include "daemon/trackerd/outbox.hpp"
#include "drivers/frame_source.hpp"
#include "drivers/reconnecting_source.hpp"
#include "libcvo/io/intrinsics_file.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/lcm/local_graph_conversion.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"

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

// Intrinsics for the sources that carry none (v4l2): the configured camera. The others bring
// their own (TUM folder, CVO_RGBD message, OpenNI2 stream).
drivers::SourceOptions source_options(const config::Config& config) {
  drivers::SourceOptions options;
  options.realtime = config.trackerd.paced;
  if (config.trackerd.source.starts_with("v4l2:")) options.intrinsics = io::load_camera(config.camera);
  return options;
}

}  // namespace

// Everything sized by the first frame. Owned by Trackerd; the tracking thread uses the tracker
// and the frame copy, both threads the outbox (thread-safe).
struct Trackerd::Pipeline {
  Pipeline(int w, int h, const odometry::KeyframeOdometryParameters& parameters)
      : width(w),
        height(h),
        tracker(w, h, parameters),
        outbox(kOutboxEvents, kPoolSlots, w, h, parameters.max_points, parameters.local_graph_capacity) {
    previous.bgr.create(h, w, CV_8UC3);
    previous.depth.create(h, w, CV_16UC1);
  }
  int width, height;
  odometry::KeyframeOdometry tracker;
  core::RgbdFrame previous;  // frame n-1: it becomes the keyframe when one is made at frame n
  Outbox outbox;
};

Trackerd::Trackerd(config::Config config) : config_(std::move(config)) {
  const auto& t = config_.trackerd;
  if (t.source.find(':') == std::string::npos)
    throw io::InputError("trackerd.source", "'" + t.source + "': expected tum:DIR, lcm:URL, openni2:URI or v4l2:DEV");
  if (!lcm::parse_colour_encoding(t.keyframe_colour_encoding))
    throw io::InputError("trackerd.keyframe_colour_encoding", "'" + t.keyframe_colour_encoding + "': expected raw, jpeg or png");
  if (t.source.starts_with("v4l2:")) (void)io::load_camera(config_.camera);  // fail now, not in a thread
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

int Trackerd::run() {
  const auto& t = config_.trackerd;
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
    source = is_device(t.source) ? std::make_unique<drivers::ReconnectingSource>(t.source, source_options(config_))
                                 : drivers::open_source(t.source, source_options(config_));
  } catch (const std::exception& e) {
    note(std::string("cannot open the frame source: ") + e.what());
    fatal_ = true;  // a folder or URL that is wrong now stays wrong; devices are retried above
    ring_->close();
    return;
  }
  note("reading " + source->describe());
  counters_.source_connected = true;

  std::int64_t next_index = 0;  // our own sequence: the tracker needs increasing indices across re-opens
  bool connected = true;
  while (!stop_) {
    RingSlot* slot = ring_->begin_write();
    if (slot == nullptr) break;  // closed
    const auto result = source->read(slot->frame, 100ms);
    counters_.source_lost_frames = static_cast<std::int64_t>(source->lost_frames());
    switch (result.status) {
      case drivers::ReadStatus::kFrame:
        slot->received = Clock::now();
        slot->frame.index = static_cast<std::uint64_t>(next_index++);
        ring_->commit_write();
        if (!connected) {
          connected = true;
          counters_.source_connected = true;
          note("frames again from " + source->describe());
        }
        continue;
      case drivers::ReadStatus::kTimeout: break;
      case drivers::ReadStatus::kBadInput: {
        const auto kind = static_cast<std::size_t>(result.bad_input);
        const auto n = ++counters_.bad_messages[std::min<std::size_t>(kind, 4)];
        if (n <= 10 || (n & (n - 1)) == 0) note("skipped bad input #" + std::to_string(n) + ": " + result.message);
        break;
      }
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

  odometry::KeyframeOdometryParameters parameters;
  parameters.selection = config_.selection;
  parameters.cvo = config_.cvo;
  parameters.keyframe = config_.keyframe;

  Pipeline* p = nullptr;
  std::int64_t keyframe_id = -1, frames = 0, allocations_at_warmup = 0;
  while (true) {
    track_heartbeat_ns_ = now_ns();
    RingSlot* slot = ring_->begin_read(100ms);
    if (slot == nullptr) {
      if (ring_->drained()) break;
      continue;
    }
    const core::RgbdFrame& frame = slot->frame;
    if (p == nullptr) {
      const auto& k = frame.intrinsics;
      if (!k.validate().empty() || frame.bgr.cols != k.width || frame.bgr.rows != k.height) {
        ++counters_.bad_messages[cvo_lcm::status_t::BAD_CONTENT];
        ring_->end_read();
        continue;
      }
      pipeline_ = std::make_unique<Pipeline>(k.width, k.height, parameters);
      p = pipeline_.get();
      pipeline_ready_ = true;
    }
    if (frame.bgr.cols != p->width || frame.bgr.rows != p->height || frame.depth.cols != p->width ||
        frame.depth.rows != p->height) {  // the first frame fixed the size; a change is a new camera
      ++counters_.bad_messages[cvo_lcm::status_t::BAD_CONTENT];
      ring_->end_read();
      continue;
    }

    const odometry::TrackResult result = p->tracker.track(frame);
    Event event;
    PoseEvent& e = event.pose;
    e.frame_index = static_cast<std::int64_t>(frame.index);
    e.timestamp = frame.timestamp;
    e.received = slot->received;
    e.status = result.status;
    e.odom_pose = result.pose;
    e.map_pose = correction_.get() * result.pose;
    e.inner_product = result.inner_product;
    e.gamma_keyframe = p->tracker.gamma();
    e.iterations = result.iterations;
    e.points = static_cast<int>(result.points);
    if (!result.tracked()) ++counters_.failed_frames;

    if (p->tracker.local_graph_closed() && keyframe_id >= 0) {
      event.graph_slot = p->outbox.acquire_graph_slot();
      if (event.graph_slot >= 0) {
        auto& g = p->outbox.graph(event.graph_slot);
        g.keyframe_id = keyframe_id;
        g.graph = p->tracker.closed_local_graph();  // within capacity: no allocation
      }
    }
    if (result.keyframe) {
      ++keyframe_id;
      ++counters_.keyframes;
      event.keyframe_slot = p->outbox.acquire_keyframe_slot();
      if (event.keyframe_slot >= 0) {
        auto& k = p->outbox.keyframe(event.keyframe_slot);
        // The keyframe is this frame (first frame, restart) or, as in the paper, frame n-1.
        const core::RgbdFrame& source = p->tracker.keyframe_index() == frame.index ? frame : p->previous;
        k.id = keyframe_id;
        k.pose = p->tracker.current_local_graph().keyframe().pose;
        k.frame.index = source.index;
        k.frame.timestamp = source.timestamp;
        k.frame.depth_timestamp = source.depth_timestamp;
        k.frame.intrinsics = source.intrinsics;
        source.bgr.copyTo(k.frame.bgr);
        source.depth.copyTo(k.frame.depth);
        k.cloud = p->tracker.keyframe_cloud();  // same capacity: copies points, no allocation
      }
    }
    e.keyframe_id = keyframe_id;
    e.is_keyframe = result.keyframe;
    // Covariance of the pose relative to its keyframe: the inverse CVO Hessian of the keyframe
    // registration (the last keyframe->frame edge), when this frame has one.
    const auto& edges = p->tracker.current_local_graph().edges();
    for (auto it = edges.rbegin(); it != edges.rend() && it != edges.rbegin() + 2; ++it)
      if (it->to == frame.index && it->from == p->tracker.keyframe_index()) {
        const Eigen::FullPivLU<core::Matrix6d> lu(it->information);
        if (lu.isInvertible()) e.covariance = lu.inverse();
      }

    // Keep frame n for the next keyframe decision (copyTo into a same-sized image: no allocation).
    p->previous.index = frame.index;
    p->previous.timestamp = frame.timestamp;
    p->previous.depth_timestamp = frame.depth_timestamp;
    p->previous.intrinsics = frame.intrinsics;
    frame.bgr.copyTo(p->previous.bgr);
    frame.depth.copyTo(p->previous.depth);
    ring_->end_read();

    p->outbox.push(event, t.deterministic);
    ++counters_.frames_tracked;
    if (++frames == static_cast<std::int64_t>(t.warmup_frames)) allocations_at_warmup = thread_allocations();
    if (frames > static_cast<std::int64_t>(t.warmup_frames))
      counters_.allocations_after_warmup = thread_allocations() - allocations_at_warmup;
  }
  if (p != nullptr) p->outbox.close();
  tracker_done_ = true;
}

// ---------------------------------------------------------------------------------------------
// cvo-publish

void Trackerd::publish_loop() {
  name_this_thread("cvo-publish");
  const auto& t = config_.trackerd;
  ::lcm::LCM lcm(t.lcm_url);
  publish_heartbeat_ns_ = now_ns();

  // CVO_MAP: the back end's keyframe poses; keyframe odometry poses are remembered as published.
  std::map<std::int64_t, core::SE3> keyframe_odom_poses;
  struct MapHandler {
    Trackerd* self;
    std::map<std::int64_t, core::SE3>* odom;
    void handle(const ::lcm::ReceiveBuffer* buffer, const std::string& /*channel*/) {
      std::string error;
      const auto map = lcm::decode<cvo_lcm::map_t>(buffer->data, static_cast<int>(buffer->data_size), &error);
      if (!map) {
        ++self->counters_.bad_messages[cvo_lcm::status_t::BAD_BODY];
        self->note("skipped CVO_MAP: " + error);
        return;
      }
      for (int i = map->num_keyframes - 1; i >= 0; --i) {  // the newest keyframe both sides know
        const auto it = odom->find(map->keyframe_ids[static_cast<std::size_t>(i)]);
        if (it == odom->end()) continue;
        const auto map_pose = lcm::from_message(map->poses[static_cast<std::size_t>(i)], &error);
        if (!map_pose) {
          ++self->counters_.bad_messages[cvo_lcm::status_t::BAD_CONTENT];
          self->note("skipped CVO_MAP: " + error);
          return;
        }
        self->correction_.set(*map_pose * it->second.inverse());
        return;
      }
    }
  } map_handler{this, &keyframe_odom_poses};
  // A file:// output is a log being written: nothing comes back on it.
  const bool receives = !t.lcm_url.starts_with("file://");
  if (receives) lcm.subscribe("CVO_MAP", &MapHandler::handle, &map_handler);

  LatencyWindow latency(1024);
  const auto encoding = lcm::RgbdEncoding{*lcm::parse_colour_encoding(t.keyframe_colour_encoding), lcm::DepthEncoding::kPng};
  std::int64_t published = 0, published_at_last_status = 0, deadline_misses = 0, failed_at_last_status = 0;
  auto last_status = Clock::now();
  auto last_frame = Clock::now();
  bool first = true;

  const auto publish_status = [&](std::int8_t state_override) {
    const auto now = Clock::now();
    const double elapsed = std::chrono::duration<double>(now - last_status).count();
    cvo_lcm::status_t s{};
    s.version = cvo_lcm::status_t::SCHEMA_VERSION;
    s.utime = wall_utime();
    s.pid = static_cast<std::int32_t>(getpid());
    s.rate_hz = elapsed > 0 ? static_cast<double>(published - published_at_last_status) / elapsed : 0;
    const auto l = latency.summary();
    s.latency_median_ms = l.median_ms;
    s.latency_p99_ms = l.p99_ms;
    s.deadline_misses = deadline_misses;
    s.dropped_frames = ring_->dropped() + counters_.source_lost_frames;
    s.failed_frames = counters_.failed_frames;
    s.source_gaps = counters_.source_gaps;
    s.allocations_after_warmup = counters_.allocations_after_warmup;
    s.queue_depth = static_cast<std::int32_t>(ring_->waiting());
    s.rss_bytes = resident_bytes();
    for (int k = 0; k < cvo_lcm::status_t::NUM_BAD_KINDS; ++k) s.bad_messages[k] = counters_.bad_messages[k];
    s.process = kProcess;
    {
      const std::lock_guard lock(detail_mutex_);
      s.detail = detail_;
    }
    const bool idle = now - last_frame > 1s;
    if (state_override >= 0) s.state = state_override;
    else if (published == 0) s.state = counters_.source_connected ? cvo_lcm::status_t::STATE_STARTING : cvo_lcm::status_t::STATE_WAITING_FOR_INPUT;
    else if (!counters_.source_connected || idle) s.state = cvo_lcm::status_t::STATE_WAITING_FOR_INPUT;
    else if (counters_.failed_frames > failed_at_last_status) s.state = cvo_lcm::status_t::STATE_DEGRADED;
    else s.state = cvo_lcm::status_t::STATE_RUNNING;
    lcm.publish("CVO_STATUS", &s);
    systemd_.status(std::to_string(published) + " frames, " + std::to_string(static_cast<int>(std::lround(s.rate_hz))) +
                    " Hz, latency p99 " + std::to_string(static_cast<int>(std::lround(s.latency_p99_ms))) + " ms, " +
                    std::to_string(s.dropped_frames) + " dropped");
    published_at_last_status = published;
    failed_at_last_status = counters_.failed_frames;
    last_status = now;
  };

  const auto publish_event = [&](const Event& event) {
    Pipeline& p = *pipeline_;
    const PoseEvent& e = event.pose;
    if (event.graph_slot >= 0) {
      const auto& g = p.outbox.graph(event.graph_slot);
      const auto message = lcm::to_message(g.graph, g.keyframe_id, wall_utime());
      lcm.publish("CVO_LOCAL_GRAPH", &message);
    }
    if (event.keyframe_slot >= 0) {
      const auto& k = p.outbox.keyframe(event.keyframe_slot);
      std::string error;
      lcm::Keyframe keyframe{k.id, k.frame, k.pose, k.cloud};
      if (const auto message = lcm::to_message(keyframe, encoding, &error)) {
        lcm.publish("CVO_KEYFRAME", &*message);
        keyframe_odom_poses[k.id] = k.pose;
      } else {
        note("keyframe " + std::to_string(k.id) + " not published: " + error);
      }
    }
    cvo_lcm::pose_t m{};
    m.version = cvo_lcm::pose_t::SCHEMA_VERSION;
    m.utime = lcm::to_utime(e.timestamp);
    m.frame_index = e.frame_index;
    m.keyframe_id = e.keyframe_id;
    m.odom_pose = lcm::to_message(e.odom_pose);
    m.map_pose = lcm::to_message(e.map_pose);
    lcm::matrix6_to_message(e.covariance, m.covariance);
    m.status = to_pose_status(e.status);
    m.is_keyframe = e.is_keyframe;
    m.inner_product = e.inner_product;
    m.gamma_frame = 0;
    m.gamma_keyframe = e.gamma_keyframe;
    m.iterations = e.iterations;
    m.points = e.points;
    m.latency_ms = std::chrono::duration<double, std::milli>(Clock::now() - e.received).count();
    lcm.publish("CVO_POSE", &m);
    latency.add(m.latency_ms);
    if (m.latency_ms > t.deadline_ms) ++deadline_misses;
    ++published;
    last_frame = Clock::now();
    p.outbox.release(event);
  };

  const int fd = receives ? lcm.getFileno() : -1;
  Event event;
  while (true) {
    publish_heartbeat_ns_ = now_ns();
    if (pipeline_ready_) {
      if (pipeline_->outbox.pop(event, 10ms)) {
        publish_event(event);
        if (first) {
          first = false;
          note("first pose published");
        }
      } else if (tracker_done_ && pipeline_->outbox.finished()) {
        break;
      }
    } else if (tracker_done_) {
      break;
    } else {
      std::this_thread::sleep_for(10ms);
    }
    if (fd >= 0) {  // CVO_MAP, without blocking the poses
      pollfd pfd{fd, POLLIN, 0};
      while (poll(&pfd, 1, 0) > 0 && (pfd.revents & POLLIN) != 0) lcm.handle();
    }
    if (Clock::now() - last_status >= std::chrono::duration<double>(t.status_period_s)) publish_status(-1);
  }
  publish_status(cvo_lcm::status_t::STATE_STOPPING);
  publisher_done_ = true;
}

}  // namespace cvo::daemon::trackerd
