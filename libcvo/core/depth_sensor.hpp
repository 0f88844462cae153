#pragma once
// A depth sensor beside the colour camera, as in RealSense and most UVC depth cameras: its own
// intrinsics (image size, lens, raw depth units per metre) and its pose in the colour camera's
// frame, the depth-to-colour extrinsic: X_colour = T_colour_depth X_depth. Its depth is not
// registered to colour until drivers/depth_registration.hpp moves it there.
#include "libcvo/core/camera.hpp"
#include "libcvo/core/se3.hpp"

namespace cvo::core {

struct DepthSensor {
  Intrinsics intrinsics;
  SE3 T_colour_depth;
};

}  // namespace cvo::core
