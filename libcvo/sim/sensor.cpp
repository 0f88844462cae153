#include "libcvo/sim/sensor.hpp"

#include <vector>

namespace cvo::sim {

SensorOptions kinect_sensor() {
  SensorOptions sensor;
  sensor.kinect_depth.enabled = true;
  sensor.colour_noise.enabled = true;
  return sensor;
}

Radiance expose(const Scene& scene, const core::Intrinsics& k, const PoseAtRowAndTime& pose,
                const ExposureOptions& exposure, const RenderOptions& options) {
  const auto at = [&](double offset) { return [&pose, offset](int row) { return pose(row, offset); }; };
  const std::vector<double> offsets = sub_exposure_offsets(exposure);
  Radiance mid;
  bool have_mid = false;
  cv::Mat sum;
  for (const double offset : offsets) {
    Radiance sub = render_radiance(scene, k, at(offset), options);
    sum = sum.empty() ? sub.bgr.clone() : sum + sub.bgr;
    if (offset == 0.0 && !have_mid) {
      mid = std::move(sub);
      have_mid = true;
    }
  }
  if (!have_mid) mid = render_radiance(scene, k, at(0.0), options);
  if (offsets.size() > 1) mid.bgr = sum / static_cast<double>(offsets.size());
  return mid;
}

core::RgbdFrame develop(const Radiance& radiance, const core::Intrinsics& k, double gain, const NoiseOptions& noise,
                        const SensorOptions& sensor, std::uint64_t seed) {
  core::RgbdFrame frame;
  frame.intrinsics = k;
  frame.bgr = develop_colour(radiance.bgr, gain, sensor.colour_noise, seed);
  frame.depth = depth_image(radiance.depth, k, noise, seed, sensor.kinect_depth);
  return frame;
}

}  // namespace cvo::sim
