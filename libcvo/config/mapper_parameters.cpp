#include "libcvo/config/mapper_parameters.hpp"

namespace cvo::config {

loop_closure::LoopDetectorParameters loop_detector_parameters(const Config& config) {
  loop_closure::LoopDetectorParameters p;
  p.loop = config.loop_closure;
  p.verification = config.loop_verification;
  p.cvo = config.cvo;
  p.selection = config.selection;
  p.odometry = config.odometry;
  p.keyframe = config.keyframe;
  p.keyframe_tracking = config.keyframe_tracking;
  return p;
}

slam::BackendParameters backend_parameters(const Config& config) { return config.pose_graph; }

slam::MapperParameters mapper_parameters(const Config& config) {
  return {loop_detector_parameters(config), backend_parameters(config), config.localization};
}

}  // namespace cvo::config
