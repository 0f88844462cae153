#pragma once
// The time a colour frame integrates light over, and the camera's automatic exposure.
//
// Motion blur. A pixel collects light for the exposure time e centred on its row's time (a rolling
// shutter shifts that time per row, render.hpp). The renderer approximates the integral over
// [-e/2, e/2] by the midpoint rule: N sub-exposures at offsets
//     t_j = e ((j + 1/2) / N - 1/2),  j = 0 .. N-1,
// each a sharp radiance image; the frame's colour is their mean. Depth is not blurred: the
// structured-light sensor has its own short IR exposure, so depth comes from the mid-exposure pose
// (offset 0). e = 0 gives the sharp frame exactly (one image). With N = 5 a 12-pixel smear is
// sampled every 3 pixels: a camera turning at fast_rpy's peak with a 10 ms exposure; enough for
// the smear to remove texture gradient as a real one does, not a photographic smear.
//
// Auto-exposure. A camera's AE loop meters each frame's brightness and moves its gain towards the
// value that would bring the metered brightness to a target, a little every frame: a first-order
// lag with time constant tau (a few frames), in log gain since gain acts multiplicatively:
//     g* = clamp(target / B, g_min, g_max)          B: mean luminance of the frame's radiance
//     log g_{i+1} = log g_i + a (log g*_i - log g_i),   a = 1 - exp(-dt / tau),  dt = 1 / rate
// so after n frames at constant brightness log(g_n / g*) = (1 - a)^n log(g_0 / g*). The gain
// multiplies colour, which then clips at 1 (colour_noise.hpp). The loop starts converged
// (g_0 = g*_0, a camera that has been running). tau = 0.1 s (3 frames at 30 Hz): consumer webcams'
// AE loops settle in a few frames to a few tens of frames; the short end keeps the brightness
// change between consecutive frames visible. target 0.45: mid-grey of the 8-bit range
// (sRGB-encoded 18% grey is ~0.46).
#include <vector>

#include <opencv2/core.hpp>

namespace cvo::sim {

struct ExposureOptions {
  double exposure_s = 0;  // 0: an instantaneous (sharp) frame
  int samples = 5;        // N, sub-exposures when exposure_s > 0
};

/// The sub-exposure offsets t_j (seconds from mid-exposure); {0} when exposure_s is 0.
std::vector<double> sub_exposure_offsets(const ExposureOptions& options);

struct AutoExposureOptions {
  bool enabled = false;
  double target = 0.45;  // mean luminance the loop aims for, in [0, 1]
  double time_constant_s = 0.1;
  double min_gain = 0.25;
  double max_gain = 4.0;
};

/// Mean luminance (Rec. 601 weights) of a linear BGR image (CV_64FC3), clipped at 1 per channel.
double mean_luminance(const cv::Mat& linear_bgr);

/// The AE loop above. Without `enabled` the gain stays 1.
class AutoExposure {
 public:
  AutoExposure(const AutoExposureOptions& options, double rate_hz);
  /// The gain the frame of brightness `brightness` is taken with; then the loop moves towards that
  /// frame's target for the next one.
  double expose(double brightness);
  /// The gain the loop aims at for brightness B: g* above.
  [[nodiscard]] double target_gain(double brightness) const;
  /// a above: the fraction of the log-gain error corrected per frame.
  [[nodiscard]] double step_fraction() const { return step_; }

 private:
  AutoExposureOptions options_;
  double step_;
  double log_gain_ = 0;
  bool started_ = false;
};

}  // namespace cvo::sim
