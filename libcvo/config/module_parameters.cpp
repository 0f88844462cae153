#include "libcvo/config/module_parameters.hpp"

namespace cvo::config {

// Structs, never fields: a module holds the core structs whole (libcvo/core/parameters.hpp).

odometry::FrameToFrameParameters frame_to_frame_parameters(const Config& config) {
  odometry::FrameToFrameParameters p;
  p.selection = config.selection;
  p.cvo = config.cvo;
  p.odometry = config.odometry;
  return p;
}

odometry::KeyframeOdometryParameters keyframe_odometry_parameters(const Config& config) {
  odometry::KeyframeOdometryParameters p;
  p.selection = config.selection;
  p.cvo = config.cvo;
  p.keyframe = config.keyframe;
  p.tracking = config.keyframe_tracking;
  p.odometry = config.odometry;
  return p;
}

odometry::OpenCvOdometryParameters opencv_odometry_parameters(const Config& config, odometry::OpenCvVariant variant) {
  odometry::OpenCvOdometryParameters p;
  p.variant = variant;
  p.selection = config.selection;
  p.odometry = config.odometry;
  return p;
}

loop_closure::LoopDetectorParameters loop_detector_parameters(const Config& config) {
  loop_closure::LoopDetectorParameters p;
  p.loop = config.loop_closure;
  p.verification = config.loop_verification;
  p.cvo = config.cvo;
  p.selection = config.selection;
  p.odometry = config.odometry;
  return p;
}

slam::BackendParameters backend_parameters(const Config& config) { return config.pose_graph; }

slam::MapperParameters mapper_parameters(const Config& config) {
  return {loop_detector_parameters(config), backend_parameters(config)};
}

io::TumOptions tum_options(const Config& config) {
  io::TumOptions options;
  options.dataset = config.dataset;
  return options;
}

}  // namespace cvo::config
