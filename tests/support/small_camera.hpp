#pragma once
// The "synthetic" camera preset at 1/factor of its size, pixel centres kept (cx = (width - 1) / 2
// stays true): tests that need image statistics or fast tracking, not full resolution.
#include "libcvo/core/camera.hpp"

namespace cvo::testing {

inline core::Intrinsics small_synthetic_camera(int factor) {
  core::Intrinsics k = *core::camera_preset("synthetic");
  k.fx /= factor;
  k.fy /= factor;
  k.cx = (k.cx + 0.5) / factor - 0.5;
  k.cy = (k.cy + 0.5) / factor - 0.5;
  k.width /= factor;
  k.height /= factor;
  return k;
}

}  // namespace cvo::testing
