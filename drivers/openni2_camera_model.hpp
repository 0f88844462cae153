#pragma once
// The intrinsics of an OpenNI2 device or recording, from what it says, in this order (the first
// that gives a focal length wins), with where they came from for the log and CVO_STATUS:
//   1. the camera file the user gives (the `camera` key): an explicit calibration overrides;
//   2. the device's own camera model (the cvo-virtual driver's kIntrinsicsProperty);
//   3. the colour stream's fields of view, else the depth stream's (OpenNI's model);
//   4. the PS1080 zero-plane distance and pixel size of the depth stream (zero_plane.hpp): what
//      OpenNI 1 / SensorKinect recordings of a Kinect v1 carry instead of a field of view;
//   5. the published focal length of the device, by its USB ids or name (factory_intrinsics.hpp),
//      as an assumption.
// Principal point at the image centre except from 1 and 2. Throws SourceError naming what is
// missing when none gives one.
#include <optional>
#include <string>

#include <openni2/OpenNI.h>

#include "libcvo/core/camera.hpp"

namespace cvo::drivers {

struct CameraModel {
  core::Intrinsics intrinsics;
  std::string
      origin;  // where they came from, e.g. "zero-plane distance 120 mm and pixel size 0.1042 mm of the depth stream"
};

CameraModel openni2_camera_model(const openni::Device& device, const openni::VideoStream& depth,
                                 const openni::VideoStream& colour, int width, int height,
                                 const std::optional<core::Intrinsics>& given, const std::string& spec);

}  // namespace cvo::drivers
