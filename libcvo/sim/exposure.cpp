#include "libcvo/sim/exposure.hpp"

#include <algorithm>
#include <cmath>

namespace cvo::sim {

std::vector<double> sub_exposure_offsets(const ExposureOptions& options) {
  if (!(options.exposure_s > 0) || options.samples <= 1) return {0.0};
  std::vector<double> offsets;
  const double n = options.samples;
  for (int j = 0; j < options.samples; ++j) offsets.push_back(options.exposure_s * ((j + 0.5) / n - 0.5));
  return offsets;
}

double mean_luminance(const cv::Mat& linear_bgr) {
  CV_Assert(linear_bgr.type() == CV_64FC3);
  double sum = 0;
  for (int v = 0; v < linear_bgr.rows; ++v) {
    const auto* row = linear_bgr.ptr<cv::Vec3d>(v);
    for (int u = 0; u < linear_bgr.cols; ++u)
      sum += 0.114 * std::min(row[u][0], 1.0) + 0.587 * std::min(row[u][1], 1.0) + 0.299 * std::min(row[u][2], 1.0);
  }
  return linear_bgr.total() > 0 ? sum / static_cast<double>(linear_bgr.total()) : 0.0;
}

AutoExposure::AutoExposure(const AutoExposureOptions& options, double rate_hz)
    : options_(options), step_(1.0 - std::exp(-1.0 / (rate_hz * options.time_constant_s))) {}

double AutoExposure::target_gain(double brightness) const {
  const double wanted = brightness > 0 ? options_.target / brightness : options_.max_gain;
  return std::clamp(wanted, options_.min_gain, options_.max_gain);
}

double AutoExposure::expose(double brightness) {
  if (!options_.enabled) return 1.0;
  const double target = std::log(target_gain(brightness));
  if (!started_) log_gain_ = target;
  started_ = true;
  const double gain = std::exp(log_gain_);
  log_gain_ += step_ * (target - log_gain_);
  return gain;
}

}  // namespace cvo::sim
