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
  Session(core::SessionId session, int width, int height, const config::Config& config)
      : id(session), tracker(width, height, config::keyframe_odometry_parameters(config)), output(width, height) {}
  core::SessionId id;
  odometry::KeyframeOdometry tracker;
  odometry::KeyframeOutput output;
};

SlamPipeline::SlamPipeline(const config::Config& config, loop_closure::Vocabulary vocabulary)
    : config_(config), mapper_(std::move(vocabulary), config::mapper_parameters(config)) {}

SlamPipeline::~SlamPipeline() = default;

void SlamPipeline::begin_session(core::SessionId session, int width, int height) {
  end_session();
  session_ = std::make_unique<Session>(session, width, height, config_);
}

odometry::TrackResult SlamPipeline::track(const core::RgbdFrame& frame) {
  Session& s = *session_;
  const odometry::TrackResult r = s.tracker.track(frame);
  const auto start = Clock::now();
  const odometry::KeyframeStep step = s.output.after_track(s.tracker, r, frame);
  if (step.closed_graph != nullptr) mapper_.add_local_graph(s.id, step.closed_graph_keyframe, *step.closed_graph);
  if (step.keyframe != nullptr)
    mapper_.add_keyframe({s.id, step.keyframe_id, *step.keyframe, step.keyframe_pose, s.tracker.keyframe_cloud()});
  s.output.keep(frame);
  statistics_.backend_ms += ms_since(start);
  return r;
}

void SlamPipeline::end_session() {
  if (!session_) return;
  const auto& open = session_->tracker.current_local_graph();
  if (!open.empty() && session_->output.keyframe_id() >= 0)
    mapper_.add_local_graph(session_->id, session_->output.keyframe_id(), open);
  session_.reset();
}

void SlamPipeline::finish() {
  const auto start = Clock::now();
  end_session();
  mapper_.finish();
  statistics_.final_ms = ms_since(start);
}

}  // namespace cvo::tools
