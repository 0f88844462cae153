#pragma once
// What a colour camera adds between the light reaching it and the 8-bit image: a gain, clipping at
// full scale, signal-dependent noise, 8-bit quantisation. Without the noise a white wall renders as
// a few exact grey levels, where a real camera gives every pixel its own value: on a texture-less
// real scene the point selector's adaptive gradient threshold then picks noise, thousands of points
// spread over uniform regions whose colours are all alike - the case the renderer must reproduce.
//
// Per channel, with x = min(1, gain * radiance) the clipped signal in [0, 1] and I = 255 x in levels:
//     sigma(I)^2 = read^2 + shot * I    (the photon-transfer model: Poisson shot noise, whose
//                                        variance grows with the signal, plus signal-independent
//                                        read noise; Foi et al. 2008, "Practical Poissonian-Gaussian
//                                        noise modeling and fitting for single-image raw-data")
//     level = clamp(round(I + sigma(I) n), 0, 255),  n standard normal from (seed, pixel, channel).
// read = 1 level, shot = 0.02 level: about 2.2 levels on a white wall (I ~ 200) and 1.4 on a dark
// one, "a few levels" of a webcam-class sensor at indoor exposure (chosen, not measured: the
// Kinect v1's colour camera has no published noise figures). Channels are independent (no Bayer
// demosaicing correlation).
#include <cstdint>

#include <opencv2/core.hpp>

namespace cvo::sim {

struct ColourNoiseOptions {
  bool enabled = false;
  double read_sigma_levels = 1.0;
  double shot_levels = 0.02;  // variance per level of signal
};

/// Noise std (8-bit levels) at signal `level` (0-255), the model above.
double colour_noise_sigma(const ColourNoiseOptions& options, double level);

/// The 8-bit image (CV_8UC3) of a linear one (CV_64FC3, any channel order, kept): gain, clipping at
/// 1, noise (when enabled; from `seed`), rounding. With gain 1 and no noise each value is
/// round(255 clamp(x, 0, 1)), the renderer's plain quantisation.
cv::Mat develop_colour(const cv::Mat& linear, double gain, const ColourNoiseOptions& options, std::uint64_t seed);

}  // namespace cvo::sim
