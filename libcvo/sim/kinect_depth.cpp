#include "libcvo/sim/kinect_depth.hpp"

#include <cmath>

#include "libcvo/sim/random.hpp"

namespace cvo::sim {

double kinect_depth_step(const KinectDepthOptions& options, double z) {
  return z * z / (options.subpixel_steps * options.focal_px * options.baseline_m);
}

double kinect_depth(const KinectDepthOptions& options, double z, std::uint64_t key) {
  if (!(z >= options.min_range_m && z <= options.max_range_m)) return 0;
  const double fb = options.focal_px * options.baseline_m;
  const double steps = options.subpixel_steps;
  const double disparity = fb / z + options.disparity_sigma_px * gaussian(key);
  const double quantised = std::round(disparity * steps) / steps;
  return quantised > 0 ? fb / quantised : 0;
}

}  // namespace cvo::sim
