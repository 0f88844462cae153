#pragma once
// The ORB keypoints of a keyframe that have depth, as 3-D points in its camera frame: what the
// initial loop pose is fitted to (paper section 5, "sparse-to-dense").
//
// Keypoint (u, v) (sub-pixel, OpenCV's convention: integer = pixel centre, the same as the
// intrinsics') reads the raw depth of its nearest pixel, z = raw / depth_scale, and is kept when
// min_depth <= z <= max_depth (raw 0 is "no measurement"); then
//   p = ((u - cx) z / fx, (v - cy) z / fy, z).
// The nearest pixel rather than an interpolation: at a depth edge interpolating mixes foreground
// and background into a point on neither, while the nearest pixel is right or a clean outlier that
// RANSAC rejects.
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/loop_closure/orb_features.hpp"

namespace cvo::loop_closure {

/// Keypoints with depth: descriptors row k (CV_8UC1, 32 bytes) belongs to points[k].
struct Keypoints3d {
  std::vector<Eigen::Vector3d> points;  // camera frame, metres
  cv::Mat descriptors;                  // points.size() x 32; shares no data with the input
};

/// The features of `frame` that have valid depth. Throws std::invalid_argument when the depth is
/// not CV_16UC1 of the colour image's size, the intrinsics do not validate, or the descriptors are
/// not one 32-byte CV_8UC1 row per keypoint.
Keypoints3d keypoints_with_depth(const OrbFeatures& features, const core::RgbdFrame& frame, double min_depth_m,
                                 double max_depth_m);

}  // namespace cvo::loop_closure
