#include "slam_pipeline.hpp"

#include <chrono>
#include <utility>

#include "libcvo/config/mapper_parameters.hpp"
#include "libcvo/config/module_parameters.hpp"
#include "libcvo/core/units.hpp"

namespace cvo::tools {
namespace {

using Clock = core::SteadyClock;
using core::ms_since;

}  // namespace

struct SlamPipeline::Session {
  Session(core::SessionId session, int width, int height, const config::Config& config,
          std::vector<io::AccelerometerSample> samples)
      : id(session),
        tracker(width, height, config::keyframe_odometry_parameters(config)),
        accelerometer(std::move(samples)),
        robot(config::robot_name(config.trackerd.robot)) {}
  core::SessionId id;
  odometry::KeyframeOdometry tracker;
  std::vector<io::AccelerometerSample> accelerometer;
  std::string robot;  // what cvo-trackerd would name (trackerd.robot)
};

SlamPipeline::SlamPipeline(const config::Config& config, loop_closure::Vocabulary vocabulary, bool map,
                           const std::optional<std::filesystem::path>& store)
    : config_(config),
      mapper_(std::move(vocabulary), config::mapper_parameters(config)),
      mapping_(map ? std::make_unique<mapping::Mapping>(config.mapping) : nullptr),
      store_(store ? std::make_unique<StoreOutput>(*store, config) : nullptr) {}

SlamPipeline::~SlamPipeline() = default;

void SlamPipeline::begin_session(core::SessionId session, int width, int height,
                                 std::vector<io::AccelerometerSample> accelerometer) {
  end_session();
  session_ = std::make_unique<Session>(session, width, height, config_, std::move(accelerometer));
}

odometry::TrackStep SlamPipeline::track(const core::RgbdFrame& frame) {
  Session& s = *session_;
  const odometry::TrackStep step = s.tracker.track(frame);
  const auto start = Clock::now();
  const double stored = statistics_.store_ms;
  if (const auto& g = step.closed_graph) add_local_graph(s.id, *g);
  if (const auto& k = step.new_keyframe) {
    to_store([&](StoreOutput& store) { store.keyframe(s.id, k->id, k->frame, k->pose, *k->cloud); });
    const auto outcome = mapper_.add_keyframe({s.id, k->id, k->frame, k->pose, *k->cloud, s.robot});
    for (const auto& merge : outcome.merges) to_store([&](StoreOutput& store) { store.merge(merge); });
    if (mapping_)
      mapping_->add_keyframe({s.id, k->id}, k->frame, io::mean_specific_force(s.accelerometer, k->frame.timestamp));
  }
  statistics_.backend_ms += ms_since(start) - (statistics_.store_ms - stored);
  return step;
}

void SlamPipeline::end_session() {
  if (!session_) return;
  if (const auto open = session_->tracker.finish()) add_local_graph(session_->id, *open);
  session_.reset();
}

// Timed apart from the back end's work (the daemon's cvo-receive does it, not cvo-backend).
template <class Write>
void SlamPipeline::to_store(Write&& write) {
  if (!store_) return;
  const auto start = Clock::now();
  write(*store_);
  statistics_.store_ms += ms_since(start);
}

void SlamPipeline::add_local_graph(core::SessionId session, const odometry::HandedLocalGraph& g) {
  to_store([&](StoreOutput& store) { store.local_graph(session, g.keyframe_id, *g.graph); });
  mapper_.add_local_graph(session, g.keyframe_id, *g.graph);
}

void SlamPipeline::finish() {
  const auto start = Clock::now();
  end_session();
  mapper_.finish();
  statistics_.final_ms = ms_since(start);
  if (mapping_) {
    const auto placing = Clock::now();
    mapping_->place(mapper_.map());
    statistics_.map_ms = ms_since(placing);
  }
}

}  // namespace cvo::tools
