#pragma once
// Depth as a Kinect v1 (PrimeSense structured light) measures it: a disparity d between the
// projected IR dot pattern and its reference image, quantised to sub-pixel steps, turned into depth
// by triangulation:
//     z = f b / d,   d measured in steps of 1/s pixel,
// so the representable depths are z_k = s f b / k (k a positive integer) and neighbouring ones are
//     dz ~ z^2 / (s f b)   apart:  about 2.9 mm at 1 m and 2.6 cm at 3 m with the constants below.
// Noise is added in disparity, where the sensor makes it (the dot correlation), before quantising,
// so the depth error grows as z^2 too: sigma_z ~ z^2 sigma_d / (f b).
//
// The constants, and where they come from:
//   f = 580 px   the IR camera's focal length at 640x480 (Khoshelham and Oude Elberink 2012,
//                "Accuracy and resolution of Kinect depth data", calibrated ~580-585 px; also the
//                ROS openni_camera default);
//   b = 0.075 m  the IR projector-camera baseline (same paper: ~7.5 cm);
//   s = 8        the disparity unit is 1/8 pixel (Konolige and Mihelich, "Technical description
//                of Kinect calibration", ROS wiki: the 11-bit raw value counts 1/8 pixel);
//   sigma_d = 0.07 px  Khoshelham and Oude Elberink's random error reaches ~4 cm at 5 m, i.e.
//                0.04 / (25 / (f b)) = 0.07 px; Nguyen, Izadi and Lovell 2012 (render.hpp's axial
//                model) give 14 mm at 3 m, 0.068 px: the two agree;
//   range 0.5 to 4.5 m  the Kinect v1 sees nothing nearer than ~0.5 m (the pattern is out of
//                focus and too bright) and the drivers drop disparities below ~10 px, the 4-5 m
//                where both papers end their data; 4.5 m is the middle of that.
// Not modelled: the 9x9 correlation window's spatial smoothing of the noise and the projector's
// one-sided shadow (holes at edges come from render.hpp's symmetric edge band instead).
#include <cstdint>

namespace cvo::sim {

struct KinectDepthOptions {
  bool enabled = false;  // everything below is ignored unless set
  double focal_px = 580.0;
  double baseline_m = 0.075;
  int subpixel_steps = 8;
  double disparity_sigma_px = 0.07;
  double min_range_m = 0.5;
  double max_range_m = 4.5;
};

/// Spacing of the representable depths near z: z^2 / (s f b) to first order (metres).
double kinect_depth_step(const KinectDepthOptions& options, double z);

/// The depth the sensor reports for a surface at true depth z (metres): disparity f b / z plus
/// Gaussian noise (standard normal drawn from `key`), rounded to 1/s pixel, back to depth; 0 (no
/// depth) outside [min_range_m, max_range_m] (the true depth) or for a non-positive disparity.
double kinect_depth(const KinectDepthOptions& options, double z, std::uint64_t key);

}  // namespace cvo::sim
