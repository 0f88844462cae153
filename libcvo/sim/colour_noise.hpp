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
// rho is the channels' noise correlation: a Bayer sensor measures one colour per pixel and
// demosaicing fills the other two from the neighbours, mostly from green, so the channels share
// most of their high-frequency noise; rho = 0.9 (chosen; the grey image's noise is then 0.97
// sigma, with independent channels it would be 0.67 sigma).
// read = 2 levels, shot = 0.25 level: 5.7 levels at mid-grey (I ~ 115, where auto-exposure puts
// a white wall), 7.4 at I = 200. Not measured on a Kinect (its colour camera has no published
// noise figures): chosen so that on a white wall the noise alone passes the point selector's
// DSO-style threshold (region median of |gradient| + 7 levels, registration/point_selection.hpp)
// in about 1 % of the pixels: 3000+ candidates spread over the uniform surfaces, as the issue
// measured on a real Kinect recording of white structure (~3000 points a frame). Less noise
// (2 levels, say) gives a few dozen points, a scene a real camera does not produce.
#include <cstdint>

#include <opencv2/core.hpp>

namespace cvo::sim {

struct ColourNoiseOptions {
  bool enabled = false;
  double read_sigma_levels = 2.0;
  double shot_levels = 0.25;         // variance per level of signal
  double channel_correlation = 0.9;  // rho
};

/// Noise std (8-bit levels) at signal `level` (0-255), the model above.
double colour_noise_sigma(const ColourNoiseOptions& options, double level);

/// The 8-bit image (CV_8UC3) of a linear one (CV_64FC3, any channel order, kept): gain, clipping at
/// 1, noise (when enabled; from `seed`), rounding. With gain 1 and no noise each value is
/// round(255 clamp(x, 0, 1)), the renderer's plain quantisation.
cv::Mat develop_colour(const cv::Mat& linear, double gain, const ColourNoiseOptions& options, std::uint64_t seed);

}  // namespace cvo::sim
