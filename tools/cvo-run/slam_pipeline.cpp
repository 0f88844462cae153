#include "slam_pipeline.hpp"

#include <chrono>
#include <utility>

namespace cvo::tools {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

odometry::KeyframeOdometryParameters tracker_parameters(const config::Config& config) {
  odometry::KeyframeOdometryParameters p;
  p.selection = config.selection;
  p.cvo = config.cvo;
  p.keyframe = config.keyframe;
  return p;
}

loop_closure::LoopDetectorParameters detector_parameters(const config::Config& config) {
  loop_closure::LoopDetectorParameters p;
  p.loop = config.loop_closure;
  p.cvo = config.cvo;
  p.selection = config.selection;
  return p;
}

}  // namespace

SlamPipeline::SlamPipeline(int width, int height, const config::Config& config, loop_closure::Vocabulary vocabulary)
    : tracker_(width, height, tracker_parameters(config)),
      selector_(width, height, config.selection),
      cloud_(tracker_.parameters().max_points),
      detector_(std::move(vocabulary), detector_parameters(config)),
      backend_(slam::BackendParameters{.cauchy_delta = config.pose_graph.cauchy_delta}) {}

odometry::TrackResult SlamPipeline::track(const core::RgbdFrame& frame) {
  const odometry::TrackResult r = tracker_.track(frame);
  const auto start = Clock::now();
  if (tracker_.local_graph_closed()) {
    const auto& graph = tracker_.closed_local_graph();
    backend_.add_local_graph(static_cast<posegraph::NodeId>(graph.keyframe().frame_index), graph);
  }
  if (r.keyframe) {
    // The first frame and a restart make the current frame the keyframe; otherwise it is n-1.
    if (tracker_.keyframe_index() == frame.index) add_keyframe(frame, r.pose);
    else if (have_previous_ && tracker_.keyframe_index() == previous_.index) add_keyframe(previous_, previous_pose_);
  }
  if (backend_.unoptimised_loops() > 0) {  // new loops, or waiting ones that just found their keyframe
    backend_.optimise_keyframes();
    detector_.update_poses(backend_.keyframe_poses());
  }
  previous_ = frame;
  previous_pose_ = r.pose;
  have_previous_ = true;
  statistics_.backend_ms += ms_since(start);
  return r;
}

void SlamPipeline::add_keyframe(const core::RgbdFrame& keyframe, const core::SE3& odometry_pose) {
  selector_.select(keyframe, cloud_);
  const auto id = static_cast<std::int64_t>(keyframe.index);
  // Its back-end pose when its graph is in (the usual case: it ended the graph just closed), else
  // the tracker's pose moved by the latest correction.
  const auto& graph = backend_.keyframe_graph();
  const core::SE3 pose = graph.contains(id) ? graph.node(id).pose : backend_.odometry_correction() * odometry_pose;
  const auto loops = detector_.add_keyframe(id, keyframe, cloud_, pose);
  statistics_.loops_tried += detector_.last_attempts().size();
  for (const auto& loop : loops) backend_.add_loop(loop);
  statistics_.loops_accepted += loops.size();
}

core::Trajectory SlamPipeline::finish() {
  const auto start = Clock::now();
  const auto& open = tracker_.current_local_graph();
  if (!open.empty()) backend_.add_local_graph(static_cast<posegraph::NodeId>(open.keyframe().frame_index), open);
  backend_.optimise_all();
  statistics_.final_ms = ms_since(start);
  return backend_.frame_trajectory();
}

}  // namespace cvo::tools
