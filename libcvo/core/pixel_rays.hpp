#pragma once
// The undistorted normalised ray of every pixel of a camera: the inverse of the lens model of
// camera.hpp, pixel (u, v) -> (x', y') with u = fx x'' + cx, x'' = distort(x', y'). Computed once
// per camera by whoever back-projects every pixel of every frame (point selection, depth
// registration), then read per pixel.
#include <vector>

#include "libcvo/core/camera.hpp"

namespace cvo::core {

/// x', y' of pixel (u, v) at [2 (v width + u)] and [2 (v width + u) + 1], for the intrinsics'
/// width x height (pixel centres at integer coordinates). Iterated until the reprojection is within
/// 1e-4 px: OpenCV's default 5 fixed-point iterations are a few tenths of a pixel short in the
/// corners of strong barrel distortion (TUM fr1).
std::vector<float> undistorted_pixel_rays(const Intrinsics& intrinsics);

}  // namespace cvo::core
