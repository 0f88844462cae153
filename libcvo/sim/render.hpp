#pragma once
// Ray-cast RGB-D rendering of an analytic scene with exact ground truth.
//
// Pixel (u, v) (integer = pixel centre, the convention of cx = (width - 1) / 2) looks along the
// camera-frame ray d = ((u - cx) / fx, (v - cy) / fy, 1). Since d_z = 1 the hit's ray parameter
// is its camera-frame z, which is what TUM depth stores:
//     raw = round(z * depth_scale),  0 when nothing is hit, z > max_depth or raw > 65535.
// Back-projecting raw depth therefore lands within 0.5 / depth_scale (in z) of the surface.
// Colour is the scene's viewpoint-independent surface colour (scene.hpp), optionally averaged
// over 2x2 sub-pixel rays (+-1/4 pixel) against aliasing; depth always comes from the centre ray.
// (Sub-rays of a pixel whose centre ray and 4-neighbours' centre rays all meet one surface are
// intersected with that surface's plane only: a feature thinner than a pixel spacing could be
// missed in colour, never in depth.)
//
// Optional structured-light noise (all from counter-based hashes of the seed and pixel index, so
// deterministic), applied to the clean depth z in this order:
//   * grazing incidence: no depth when the angle between the viewing ray and the normal exceeds
//     grazing_angle_deg;
//   * depth discontinuities: no depth within edge_band_px pixels (Chebyshev) of a neighbour that
//     has no surface or whose depth differs by more than edge_jump_fraction * z;
//   * random dropout with dropout_probability;
//   * axial Gaussian noise of std sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2 m (Nguyen, Izadi and
//     Lovell 2012, Kinect v1, valid for moderate incidence angles).
// Or, with KinectDepthOptions (kinect_depth.hpp), the sensor's own model instead of the axial
// noise: disparity noise and 1/8-pixel quantisation, and its range; the holes above (with the
// NoiseOptions values, enabled or not) come with it.
//
// render() is render_radiance() (the linear colour and the centre rays' depth, what the scene
// sends to the camera) followed by develop_colour() (colour_noise.hpp, gain 1, no noise) and
// depth_image(): sensor.hpp composes the same steps with exposure, gain and colour noise.
#include <cstdint>
#include <functional>
#include <vector>

#include <opencv2/core.hpp>

#include "libcvo/core/camera.hpp"
#include "libcvo/core/depth_sensor.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/sim/kinect_depth.hpp"
#include "libcvo/sim/scene.hpp"

namespace cvo::sim {

struct NoiseOptions {
  bool enabled = false;  // everything below is ignored unless set
  double grazing_angle_deg = 75.0;
  int edge_band_px = 1;
  double edge_jump_fraction = 0.05;
  double dropout_probability = 0.01;
  bool axial = true;
};

struct RenderOptions {
  double max_depth = 8.0;   // metres (camera z)
  bool supersample = true;  // 2x2 colour rays per pixel
};

/// Axial depth noise std (metres) at depth z (metres), Nguyen et al. 2012.
double axial_noise_sigma(double z);

/// Renders one frame seen from T_world_camera. `seed` drives the depth noise only (the texture is
/// the scene's); index and timestamps of the result are 0. Throws std::invalid_argument when the
/// intrinsics do not validate.
core::RgbdFrame render(const Scene& scene, const core::Intrinsics& intrinsics, const core::SE3& T_world_camera,
                       const NoiseOptions& noise = {}, std::uint64_t seed = 0, const RenderOptions& options = {});

/// A rolling-shutter frame (core::Intrinsics::readout_s): row v seen from T_world_camera_at_row(v),
/// colour and depth alike; the frame above is the case of one pose for every row.
using PoseAtRow = std::function<core::SE3(int row)>;
core::RgbdFrame render(const Scene& scene, const core::Intrinsics& intrinsics, const PoseAtRow& T_world_camera_at_row,
                       const NoiseOptions& noise = {}, std::uint64_t seed = 0, const RenderOptions& options = {});

/// The frame a camera with a separate depth sensor delivers, before registration: colour seen from
/// T_world_colour through `colour`, depth seen by `depth` from T_world_colour * T_colour_depth, at
/// the depth sensor's own size and units. frame.intrinsics is the colour camera's. Rendering the
/// same pose with render() gives the exact registered depth to compare with.
/// What a pixel's centre ray meets: z = 0 means no surface within range.
struct DepthSample {
  double z = 0;
  double cos_incidence = 1;  // |cos| of the angle between viewing ray and surface normal
  int surface = -1;          // whatever the range
};

/// The light reaching the camera, before any sensor: colour (CV_64FC3, BGR, linear, averaged over
/// the sub-pixel rays when supersampling) and the clean centre-ray depth of every pixel, row-major.
struct Radiance {
  cv::Mat bgr;
  std::vector<DepthSample> depth;
};
Radiance render_radiance(const Scene& scene, const core::Intrinsics& intrinsics, const PoseAtRow& T_world_camera_at_row,
                         const RenderOptions& options = {});

/// The 16-bit depth image (CV_16UC1, intrinsics.depth_scale) of clean samples through the noise
/// model and, when enabled, the Kinect model (header comment); `seed` drives both.
cv::Mat depth_image(const std::vector<DepthSample>& clean, const core::Intrinsics& intrinsics,
                    const NoiseOptions& noise, std::uint64_t seed, const KinectDepthOptions& kinect = {});

core::RgbdFrame render_separate_depth(const Scene& scene, const core::Intrinsics& colour,
                                      const core::DepthSensor& depth, const core::SE3& T_world_colour,
                                      const NoiseOptions& noise = {}, std::uint64_t seed = 0,
                                      const RenderOptions& options = {});

}  // namespace cvo::sim
