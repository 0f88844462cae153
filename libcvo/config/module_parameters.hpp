#pragma once
// The one place the configuration becomes each module's parameters. cvo-run, cvo-trackerd,
// cvo-backendd and the benchmarks build their trackers, loop detector and back end from these
// functions and nowhere else, so a key of the table (config.cpp) reaches every program the same
// way. Each module's parameter struct holds the core structs whole, so these functions copy
// structs, not fields: a new tunable is a field in libcvo/core/parameters.hpp (its default) and a
// row in config.cpp's table (its key, range and doc), with default.yaml regenerated; nothing here.
//
// Which keys go where:
//   selection.*, cvo.*                   every CVO tracker and the loop detector's refinement
//   odometry.max_points                  every point cloud's capacity (trackers, loop detector)
//   odometry.restart_after_failures      the frame-to-frame trackers (cvo, opencv-*)
//   keyframe.*                           KF-CVO
//   selection.min/max_depth_m            also OpenCV's odometry and the loop keypoints' depth range
//   loop_closure.*                       the loop detector (detection, RANSAC, ORB, refinement)
//   pose_graph.*                         the back end's optimisations
//   dataset.*                            reading TUM-layout folders
// The daemons' own sections (trackerd, backendd) and camera are read by the daemons themselves.
//
// Kept apart from cvo::config (the file format) so that reading a configuration does not link the
// modules: this is target cvo::module_parameters, the tracking side (odometry, datasets); the
// loop detector's and the back end's (loop_closure.*, loop_verification.*, pose_graph.*) are
// mapper_parameters.hpp's, target cvo::mapper_parameters, so that cvo-trackerd does not link the
// back end.
#include "libcvo/config/config.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/odometry/frame_to_frame.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"
#include "libcvo/odometry/opencv_odometry.hpp"

namespace cvo::config {

/// cvo-run --mode cvo: the paper's frame-to-frame baseline.
odometry::FrameToFrameParameters frame_to_frame_parameters(const Config& config);
/// KF-CVO: cvo-run --mode kf-cvo and slam, cvo-trackerd, bench/odometry_stages.
odometry::KeyframeOdometryParameters keyframe_odometry_parameters(const Config& config);
/// OpenCV's RGB-D odometry (cvo-run --mode opencv-rgbd, opencv-rgbd-icp): the depth range and the
/// failure policy; everything else is OpenCV's own.
odometry::OpenCvOdometryParameters opencv_odometry_parameters(const Config& config, odometry::OpenCvVariant variant);

/// Reading TUM-layout folders: the association window (the caller adds intrinsics and max_frames).
io::TumOptions tum_options(const Config& config);

}  // namespace cvo::config
