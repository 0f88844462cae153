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
//     level_c = clamp(round(I_c + sigma(I_c) (sqrt(rho) n + sqrt(1 - rho) n_c)), 0, 255)
// with n, n_c standard normals from (seed, pixel): n common to the channels, n_c each its own.
// rho is the channels' noise correlation.
// The defaults are measured on real Kinect frames, TUM fr1/rpy (fitted) and fr1/desk (checked), by
// what the tracker sees of the noise: the grey image at the pixel scale. The residual of the
// flattest fifth of 8x8 grey patches (a plane removed) is 0.79 levels on fr1/rpy and 0.59 on
// fr1/desk, Immerkær's Laplacian estimate 0.74 and 0.49; per channel the flattest patches show no
// growth with the signal (the shot term fits at or below zero). So: read = 1.2 levels, shot = 0,
// rho = 0, a grey noise of 0.67 * 1.2 = 0.8 levels (bench/odometry-tuning.md, "What the white room
// shows"). The channels' own spread on fr1 is larger (1.5-1.9 levels: their noise is partly
// anti-correlated, chroma noise, which this model cannot hold); the colour kernel (ℓ_c = 0.1, 25
// levels) does not see the difference. Until issue 47 the defaults were read = 2, shot = 0.25,
// rho = 0.9, 5.7 levels at mid-grey, chosen so that noise passed the selector's threshold: seven
// times a real camera's, which made the rendered white room hard for reasons a real one is not.
#include <cstdint>

#include <opencv2/core.hpp>

namespace cvo::sim {

struct ColourNoiseOptions {
  bool enabled = false;
  double read_sigma_levels = 1.2;
  double shot_levels = 0.0;          // variance per level of signal
  double channel_correlation = 0.0;  // rho
};

/// Noise std (8-bit levels) at signal `level` (0-255), the model above.
double colour_noise_sigma(const ColourNoiseOptions& options, double level);

/// The 8-bit image (CV_8UC3) of a linear one (CV_64FC3, any channel order, kept): gain, clipping at
/// 1, noise (when enabled; from `seed`), rounding. With gain 1 and no noise each value is
/// round(255 clamp(x, 0, 1)), the renderer's plain quantisation.
cv::Mat develop_colour(const cv::Mat& linear, double gain, const ColourNoiseOptions& options, std::uint64_t seed);

}  // namespace cvo::sim
