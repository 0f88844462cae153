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

io::TumOptions tum_options(const Config& config) {
  io::TumOptions options;
  options.dataset = config.dataset;
  return options;
}

}  // namespace cvo::config
