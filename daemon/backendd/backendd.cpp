#include "daemon/backendd/backendd.hpp"

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <iostream>
#include <optional>
#include <thread>
#include <utility>

#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/local_graph_t.hpp"
#include "cvo_lcm/map_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "daemon/common/realtime.hpp"
#include "daemon/common/signals.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/lcm/local_graph_conversion.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "libcvo/loop_closure/loop_detector.hpp"
#include "libcvo/slam/backend.hpp"

namespace cvo::daemon::backendd {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
constexpr const char* kProcess = "cvo-backendd";

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}
std::int64_t wall_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

std::filesystem::path resolve_vocabulary(const std::string& setting) {
  return setting == "default" ? loop_closure::default_vocabulary_file() : std::filesystem::path(setting);
}

// Everything the cvo-backend thread owns.
struct Backendd::Work {
  Work(loop_closure::Vocabulary vocabulary, const config::Config& config)
      : detector(std::move(vocabulary), detector_parameters(config)),
        backend(slam::BackendParameters{config.pose_graph.cauchy_delta, 1.0, 100}) {}

  static loop_closure::LoopDetectorParameters detector_parameters(const config::Config& config) {
    loop_closure::LoopDetectorParameters p;
    p.loop = config.loop_closure;
    p.cvo = config.cvo;
    return p;
  }

  loop_closure::LoopDetector detector;
  slam::Backend backend;
  std::map<std::int64_t, std::int64_t> keyframe_id_of_frame;  // frame index -> tracker keyframe id
  std::map<std::int64_t, core::SE3> odometry_pose_of_frame;   // keyframes' tracker poses
  std::vector<loop_closure::LoopClosure> loops;
  std::int64_t revision = 0, keyframes = 0, local_graphs = 0, loops_tried = 0;
};

Backendd::Backendd(config::Config config) : config_(std::move(config)) {
  const auto& b = config_.backendd;
  const auto vocabulary = loop_closure::Vocabulary::load(resolve_vocabulary(b.vocabulary));
  work_ = std::make_unique<Work>(vocabulary, config_);
  std::string warning;
  store_ = std::make_unique<KeyframeStore>(b.store, recovered_, warning);
  if (!warning.empty()) note("warning: " + warning);
  ::lcm::LCM probe(b.lcm_url);
  if (!probe.good()) throw io::InputError("backendd.lcm_url", "cannot open LCM provider '" + b.lcm_url + "'");
}

Backendd::~Backendd() = default;

void Backendd::note(const std::string& detail) {
  std::cerr << kProcess << ": " << detail << std::endl;
  const std::lock_guard lock(detail_mutex_);
  detail_ = detail;
}

int Backendd::run() {
  note("store " + store_->file().string() + " (" + std::to_string(recovered_.size()) + " records recovered), LCM " +
       config_.backendd.lcm_url);
  {
    const std::lock_guard lock(queue_mutex_);
    for (auto& r : recovered_) queue_.push_back(std::move(r));  // replayed first, in order
    recovered_.clear();
  }
  std::thread receive([this] { receive_loop(); });
  std::thread work([this] { work_loop(); });
  systemd_.ready();
  auto last_watchdog = Clock::now();
  while (true) {
    if (const auto signal = wait_for_stop_signal(50ms)) {
      note(std::string("stopping on ") + (*signal == SIGTERM ? "SIGTERM" : "SIGINT"));
      break;
    }
    if (const auto period = systemd_.watchdog_period(); period && Clock::now() - last_watchdog >= *period) {
      // The worker may be inside a long optimisation: allow it the watchdog's full interval.
      const auto fresh = [&](const std::atomic<std::int64_t>& heartbeat) {
        return now_ns() - heartbeat.load() < std::chrono::nanoseconds(30s).count();
      };
      if (fresh(receive_heartbeat_ns_) && fresh(work_heartbeat_ns_)) systemd_.watchdog();
      last_watchdog = Clock::now();
    }
  }
  systemd_.stopping();
  stop_ = true;
  receive.join();
  queue_ready_.notify_all();
  work.join();
  return 0;
}

// ---------------------------------------------------------------------------------------------
// cvo-receive: nothing but decoding, checking and storing, so that no message waits on the
// back end's work and every accepted record is on disk before it is used.

void Backendd::receive_loop() {
  name_this_thread("cvo-receive");
  ::lcm::LCM lcm(config_.backendd.lcm_url);
  struct Handler {
    Backendd* self;
    void handle(const ::lcm::ReceiveBuffer* buffer, const std::string& channel) {
      std::string error;
      lcm::DecodeFailure failure{};
      const auto size = static_cast<int>(buffer->data_size);
      // Decoded (the wire is sound) and converted (the content is usable), or refused by kind.
      std::optional<std::size_t> bad;
      if (channel == "CVO_KEYFRAME") {
        const auto m = lcm::decode<cvo_lcm::keyframe_t>(buffer->data, size, &error, &failure);
        if (!m) bad = static_cast<std::size_t>(failure);
        else if (!lcm::from_message(*m, &error)) bad = cvo_lcm::status_t::BAD_CONTENT;
      } else {
        const auto m = lcm::decode<cvo_lcm::local_graph_t>(buffer->data, size, &error, &failure);
        if (!m) bad = static_cast<std::size_t>(failure);
        else if (!lcm::from_message(*m, &error)) bad = cvo_lcm::status_t::BAD_CONTENT;
      }
      if (bad) {
        ++self->bad_messages_[std::min<std::size_t>(*bad, 4)];
        self->note("skipped " + channel + ": " + error);
        return;
      }
      StoredRecord record{channel == "CVO_KEYFRAME" ? RecordKind::kKeyframe : RecordKind::kLocalGraph,
                          std::vector<std::uint8_t>(static_cast<const std::uint8_t*>(buffer->data),
                                                    static_cast<const std::uint8_t*>(buffer->data) + size)};
      try {
        self->store_->append(record.kind, record.payload);
      } catch (const std::exception& e) {
        self->note(std::string("warning: not stored (will be lost on restart): ") + e.what());
      }
      {
        const std::lock_guard lock(self->queue_mutex_);
        self->queue_.push_back(std::move(record));
      }
      self->queue_ready_.notify_one();
    }
  } handler{this};
  lcm.subscribe("CVO_KEYFRAME", &Handler::handle, &handler);
  lcm.subscribe("CVO_LOCAL_GRAPH", &Handler::handle, &handler);
  while (!stop_) {
    receive_heartbeat_ns_ = now_ns();
    if (lcm.handleTimeout(100) < 0) {
      note("LCM receive failed; retrying");
      std::this_thread::sleep_for(100ms);
    }
  }
  receiver_done_ = true;
}

// ---------------------------------------------------------------------------------------------
// cvo-backend

void Backendd::work_loop() {
  name_this_thread("cvo-backend");
  ::lcm::LCM lcm(config_.backendd.lcm_url);
  Work& w = *work_;

  const auto publish_map = [&] {
    cvo_lcm::map_t m{};
    m.version = cvo_lcm::map_t::SCHEMA_VERSION;
    m.utime = wall_utime();
    m.revision = ++w.revision;
    const auto optimised = w.backend.keyframe_poses();
    const core::SE3 correction = w.backend.odometry_correction();
    for (const auto& [frame, id] : w.keyframe_id_of_frame) {
      const auto it = optimised.find(frame);
      // A keyframe whose local graph has not closed yet follows the newest correction.
      const core::SE3 pose = it != optimised.end() ? it->second : correction * w.odometry_pose_of_frame.at(frame);
      m.keyframe_ids.push_back(id);
      m.poses.push_back(lcm::to_message(pose));
    }
    for (const auto& loop : w.loops) {
      cvo_lcm::graph_edge_t e{};
      e.from = w.keyframe_id_of_frame.count(loop.from) ? w.keyframe_id_of_frame.at(loop.from) : loop.from;
      e.to = w.keyframe_id_of_frame.count(loop.to) ? w.keyframe_id_of_frame.at(loop.to) : loop.to;
      e.measurement = lcm::to_message(loop.measurement);
      lcm::matrix6_to_message(loop.information, e.information);
      m.loops.push_back(e);
    }
    m.num_keyframes = static_cast<std::int32_t>(m.keyframe_ids.size());
    m.num_loops = static_cast<std::int32_t>(m.loops.size());
    lcm.publish("CVO_MAP", &m);
  };

  const auto process = [&](const StoredRecord& record) {
    std::string error;
    const auto size = static_cast<int>(record.payload.size());
    if (record.kind == RecordKind::kLocalGraph) {
      const auto m = lcm::decode<cvo_lcm::local_graph_t>(record.payload.data(), size, &error);
      const auto graph = m ? lcm::from_message(*m, &error) : std::nullopt;
      if (!graph) return note("stored local graph unreadable: " + error);
      try {
        w.backend.add_local_graph(static_cast<std::int64_t>(graph->keyframe().frame_index), *graph);
        ++w.local_graphs;
      } catch (const std::exception& e) {
        return note(std::string("local graph refused: ") + e.what());
      }
      publish_map();
      return;
    }
    const auto m = lcm::decode<cvo_lcm::keyframe_t>(record.payload.data(), size, &error);
    auto keyframe = m ? lcm::from_message(*m, &error) : std::nullopt;
    if (!keyframe) return note("stored keyframe unreadable: " + error);
    const auto frame = static_cast<std::int64_t>(keyframe->frame.index);
    if (w.keyframe_id_of_frame.count(frame)) return;  // a duplicate (e.g. re-sent): already known
    w.keyframe_id_of_frame[frame] = keyframe->id;
    w.odometry_pose_of_frame[frame] = keyframe->pose;
    ++w.keyframes;
    const auto poses = w.backend.keyframe_poses();
    const auto it = poses.find(frame);
    const core::SE3 pose = it != poses.end() ? it->second : w.backend.odometry_correction() * keyframe->pose;
    const auto loops = w.detector.add_keyframe(frame, keyframe->frame, keyframe->cloud, pose);
    w.loops_tried += static_cast<std::int64_t>(w.detector.last_attempts().size());
    for (const auto& loop : loops) {
      w.backend.add_loop(loop);
      w.loops.push_back(loop);
      note("loop accepted: keyframe " + std::to_string(keyframe->id) + " (frame " + std::to_string(loop.to) +
           ") to frame " + std::to_string(loop.from) + ", alpha " + std::to_string(loop.alpha));
    }
    if (w.backend.unoptimised_loops() > 0) {
      w.backend.optimise_keyframes();
      w.detector.update_poses(w.backend.keyframe_poses());
    }
    publish_map();
  };

  auto last_status = Clock::now();
  std::int64_t processed = 0, processed_at_last_status = 0;
  const auto publish_status = [&](std::int8_t state) {
    const auto now = Clock::now();
    cvo_lcm::status_t s{};
    s.version = cvo_lcm::status_t::SCHEMA_VERSION;
    s.utime = wall_utime();
    s.pid = static_cast<std::int32_t>(getpid());
    s.state = state;
    const double elapsed = std::chrono::duration<double>(now - last_status).count();
    s.rate_hz = elapsed > 0 ? static_cast<double>(processed - processed_at_last_status) / elapsed : 0;
    {
      const std::lock_guard lock(queue_mutex_);
      s.queue_depth = static_cast<std::int32_t>(queue_.size());
    }
    s.rss_bytes = resident_bytes();
    for (int k = 0; k < cvo_lcm::status_t::NUM_BAD_KINDS; ++k) s.bad_messages[k] = bad_messages_[k];
    s.process = kProcess;
    {
      const std::lock_guard lock(detail_mutex_);
      s.detail = detail_;
    }
    lcm.publish("CVO_STATUS", &s);
    systemd_.status(std::to_string(w.keyframes) + " keyframes, " + std::to_string(w.loops.size()) + " loops, map revision " +
                    std::to_string(w.revision));
    processed_at_last_status = processed;
    last_status = now;
  };

  while (true) {
    work_heartbeat_ns_ = now_ns();
    std::optional<StoredRecord> record;
    {
      std::unique_lock lock(queue_mutex_);
      queue_ready_.wait_for(lock, 50ms, [&] { return !queue_.empty() || receiver_done_; });
      if (!queue_.empty()) {
        record = std::move(queue_.front());
        queue_.pop_front();
      } else if (receiver_done_) {
        break;
      }
    }
    if (record) {
      process(*record);
      ++processed;
    }
    if (Clock::now() - last_status >= std::chrono::duration<double>(config_.backendd.status_period_s))
      publish_status(w.keyframes == 0 ? cvo_lcm::status_t::STATE_WAITING_FOR_INPUT : cvo_lcm::status_t::STATE_RUNNING);
  }
  // The final global optimisation, and the map it gives.
  if (w.backend.local_graphs() > 0) {
    const auto report = w.backend.optimise_all();
    note("final optimisation: cost " + std::to_string(report.initial_cost) + " -> " + std::to_string(report.final_cost) +
         " in " + std::to_string(report.iterations) + " iterations");
  }
  publish_map();
  note(std::to_string(w.keyframes) + " keyframes, " + std::to_string(w.local_graphs) + " local graphs, " +
       std::to_string(w.loops.size()) + " loops accepted of " + std::to_string(w.loops_tried) + " tried");
  publish_status(cvo_lcm::status_t::STATE_STOPPING);
}

}  // namespace cvo::daemon::backendd
