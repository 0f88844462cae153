#pragma once
// A camera between the scene and the RGB-D frame: the effects that make real sensors hard for a
// tracker, composed in the order light meets them:
//   1. exposure: colour integrated over the exposure time (exposure.hpp), each row at its own time
//      under a rolling shutter; depth from the mid-exposure pose;
//   2. gain from the auto-exposure loop (exposure.hpp; the caller keeps the loop's state: it
//      spans frames), clipping at full scale, colour noise, 8-bit quantisation (colour_noise.hpp);
//   3. depth through the structured-light noise (render.hpp) or the Kinect model
//      (kinect_depth.hpp).
// With everything off this is render() exactly (same bytes).
#include <cstdint>
#include <functional>

#include "libcvo/core/camera.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/sim/colour_noise.hpp"
#include "libcvo/sim/exposure.hpp"
#include "libcvo/sim/kinect_depth.hpp"
#include "libcvo/sim/render.hpp"
#include "libcvo/sim/scene.hpp"

namespace cvo::sim {

struct SensorOptions {
  KinectDepthOptions kinect_depth;
  ColourNoiseOptions colour_noise;
  ExposureOptions exposure;
  AutoExposureOptions auto_exposure;
};

/// `cvo-render --sensor kinect`: the Kinect depth model and colour noise on (exposure and
/// auto-exposure have flags of their own).
SensorOptions kinect_sensor();

/// T_world_camera of row `row` at `offset_s` seconds from the frame's mid-exposure.
using PoseAtRowAndTime = std::function<core::SE3(int row, double offset_s)>;

/// Light collected over the exposure: the mean linear colour of the sub-exposures and the clean
/// depth of the mid-exposure pose (render_radiance's, rendered once when a sub-exposure is at 0).
Radiance expose(const Scene& scene, const core::Intrinsics& intrinsics, const PoseAtRowAndTime& pose,
                const ExposureOptions& exposure, const RenderOptions& options = {});

/// The frame the sensor delivers from `radiance` taken with `gain`: colour through
/// develop_colour, depth through depth_image, both drawing on `seed`. Index and stamps are 0.
core::RgbdFrame develop(const Radiance& radiance, const core::Intrinsics& intrinsics, double gain,
                        const NoiseOptions& noise, const SensorOptions& sensor, std::uint64_t seed);

}  // namespace cvo::sim
