#include "libcvo/sim/colour_noise.hpp"

#include <algorithm>
#include <cmath>

#include "libcvo/sim/random.hpp"

namespace cvo::sim {
namespace {

constexpr std::uint64_t kColourTag = 3;  // render.cpp's depth noise uses tags 1 and 2

}  // namespace

double colour_noise_sigma(const ColourNoiseOptions& options, double level) {
  return std::sqrt(options.read_sigma_levels * options.read_sigma_levels + options.shot_levels * std::max(level, 0.0));
}

cv::Mat develop_colour(const cv::Mat& linear, double gain, const ColourNoiseOptions& options, std::uint64_t seed) {
  CV_Assert(linear.type() == CV_64FC3);
  cv::Mat out(linear.size(), CV_8UC3);
  const double common = std::sqrt(options.channel_correlation), own = std::sqrt(1.0 - options.channel_correlation);
  for (int v = 0; v < linear.rows; ++v) {
    const auto* in = linear.ptr<cv::Vec3d>(v);
    auto* bytes = out.ptr<cv::Vec3b>(v);
    for (int u = 0; u < linear.cols; ++u) {
      const auto index = static_cast<std::uint64_t>(v) * static_cast<std::uint64_t>(linear.cols) + u;
      const double shared = options.enabled ? gaussian(hash(seed, index, kColourTag, 3)) : 0.0;
      for (int c = 0; c < 3; ++c) {
        double level = std::clamp(gain * in[u][c], 0.0, 1.0) * 255.0;
        if (options.enabled)
          level += colour_noise_sigma(options, level) *
                   (common * shared + own * gaussian(hash(seed, index, kColourTag, static_cast<std::uint64_t>(c))));
        bytes[u][c] = static_cast<std::uint8_t>(std::clamp(std::lround(level), 0L, 255L));
      }
    }
  }
  return out;
}

}  // namespace cvo::sim
