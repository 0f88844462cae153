#include "libcvo/config/mapper_parameters.hpp"

namespace cvo::config {

loop_closure::OrbParameters orb_parameters(const Config& config) {
  const auto& v = config.loop_verification;
  loop_closure::OrbParameters p;
  p.features = v.orb_features;
  p.scale_factor = static_cast<float>(v.orb_scale_factor);
  p.levels = v.orb_levels;
  p.edge_threshold = v.orb_edge_threshold;
  p.fast_threshold = v.orb_fast_threshold;
  return p;
}

loop_closure::LoopDetectorParameters loop_detector_parameters(const Config& config) {
  const auto& v = config.loop_verification;
  loop_closure::LoopDetectorParameters p;
  p.loop = config.loop_closure;
  p.cvo = config.cvo;
  p.orb = orb_parameters(config);
  p.ransac_iterations = v.ransac_iterations;
  p.ransac_inlier_m = v.ransac_inlier_m;
  p.min_inliers = v.min_inliers;
  p.min_inlier_retention = v.min_inlier_retention;
  p.max_refinements = v.max_refinements;
  p.max_points = config.odometry.max_points;
  p.selection = config.selection;
  p.ransac_seed = v.ransac_seed;
  return p;
}

slam::BackendParameters backend_parameters(const Config& config) {
  slam::BackendParameters p;
  p.cauchy_delta = config.pose_graph.cauchy_delta;
  p.bridge_information = config.pose_graph.bridge_information;
  p.max_iterations = config.pose_graph.max_iterations;
  return p;
}

slam::MapperParameters mapper_parameters(const Config& config) {
  return {loop_detector_parameters(config), backend_parameters(config)};
}

}  // namespace cvo::config
