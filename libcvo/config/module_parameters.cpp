#include "libcvo/config/module_parameters.hpp"

namespace cvo::config {

odometry::FrameToFrameParameters frame_to_frame_parameters(const Config& config) {
  odometry::FrameToFrameParameters p;
  p.selection = config.selection;
  p.cvo = config.cvo;
  p.max_points = config.odometry.max_points;
  p.restart_after_failures = config.odometry.restart_after_failures;
  return p;
}

odometry::KeyframeOdometryParameters keyframe_odometry_parameters(const Config& config) {
  odometry::KeyframeOdometryParameters p;
  p.selection = config.selection;
  p.cvo = config.cvo;
  p.keyframe = config.keyframe;
  p.max_points = config.odometry.max_points;
  p.local_graph_capacity = config.keyframe_tracking.local_graph_capacity;
  p.gamma_ell = config.keyframe_tracking.gamma_ell;
  p.gamma_sigma = config.keyframe_tracking.gamma_sigma;
  p.gamma_stride = config.keyframe_tracking.gamma_stride;
  p.chain_weight = config.keyframe_tracking.chain_weight;
  p.chain_full_weight_deg = config.keyframe_tracking.chain_full_weight_deg;
  return p;
}

odometry::OpenCvOdometryParameters opencv_odometry_parameters(const Config& config, odometry::OpenCvVariant variant) {
  odometry::OpenCvOdometryParameters p;
  p.variant = variant;
  p.min_depth_m = config.selection.min_depth_m;
  p.max_depth_m = config.selection.max_depth_m;
  p.restart_after_failures = config.odometry.restart_after_failures;
  return p;
}

io::TumOptions tum_options(const Config& config) {
  io::TumOptions options;
  options.max_association_dt = config.dataset.max_association_dt;
  return options;
}

}  // namespace cvo::config
