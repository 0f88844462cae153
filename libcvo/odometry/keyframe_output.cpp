#include "libcvo/odometry/keyframe_output.hpp"

namespace cvo::odometry {

KeyframeOutput::KeyframeOutput(int width, int height) {
  previous_.bgr.create(height, width, CV_8UC3);
  previous_.depth.create(height, width, CV_16UC1);
}

KeyframeStep KeyframeOutput::after_track(const KeyframeOdometry& tracker, const TrackResult& result,
                                         const core::RgbdFrame& frame) {
  KeyframeStep step;
  if (tracker.local_graph_closed() && keyframe_id_ >= 0) {
    step.closed_graph = &tracker.closed_local_graph();
    step.closed_graph_keyframe = keyframe_id_;
  }
  if (!result.keyframe) return step;
  ++keyframe_id_;
  step.keyframe_id = keyframe_id_;
  step.keyframe_pose = tracker.current_local_graph().keyframe().pose;
  if (tracker.keyframe_index() == frame.index) step.keyframe = &frame;
  else if (have_previous_ && tracker.keyframe_index() == previous_.index) step.keyframe = &previous_;
  return step;
}

void KeyframeOutput::keep(const core::RgbdFrame& frame) {
  previous_.index = frame.index;
  previous_.timestamp = frame.timestamp;
  previous_.depth_timestamp = frame.depth_timestamp;
  previous_.intrinsics = frame.intrinsics;
  frame.bgr.copyTo(previous_.bgr);
  frame.depth.copyTo(previous_.depth);
  have_previous_ = true;
}

void KeyframeOutput::reset() {
  have_previous_ = false;
  keyframe_id_ = -1;
}

}  // namespace cvo::odometry
