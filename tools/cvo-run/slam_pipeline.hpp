#pragma once
// cvo-run's SLAM mode: the paper's whole pipeline (its figure "Pipeline for CVO SLAM"), offline
// and in one thread, frame by frame:
//   every frame       KF-CVO tracks it (odometry::KeyframeOdometry);
//   a closed graph    -> slam::Backend::add_local_graph (optimised with its keyframe fixed);
//   a new keyframe    -> the loop detector (loop_closure::LoopDetector) gets its images, its CVO
//                        points (registration::PointSelector with config.selection) and its
//                        current back-end pose; accepted loops -> Backend::add_loop, then
//                        optimise_keyframes and the detector's poses updated;
//   finish()          -> the open local graph closed, the global optimisation (optimise_all).
// The keyframe made at frame n is frame n-1 (the paper's rule), so the previous frame is kept
// (cv::Mat shares the images: nothing is copied). The tracker never sees the corrections: it
// runs in its own odometry frame, and the back end works on relative poses.
#include <cstddef>

#include "libcvo/config/config.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/loop_closure/loop_detector.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"
#include "libcvo/odometry/track_result.hpp"
#include "libcvo/registration/point_cloud.hpp"
#include "libcvo/registration/point_selection.hpp"
#include "libcvo/slam/backend.hpp"

namespace cvo::tools {

struct SlamStatistics {
  std::size_t loops_accepted = 0;
  std::size_t loops_tried = 0;  // candidates the detector verified
  double backend_ms = 0;        // local graphs, loop detection, keyframe optimisations: whole run
  double final_ms = 0;          // finish(): the last local graph and the global optimisation
};

class SlamPipeline {
 public:
  SlamPipeline(int width, int height, const config::Config& config, loop_closure::Vocabulary vocabulary);

  /// Tracks the frame, then does the back end's share of work for it (see above).
  odometry::TrackResult track(const core::RgbdFrame& frame);

  /// Closes the open local graph, runs the global optimisation and returns the back end's pose of
  /// every frame it holds (slam::correct_trajectory fills in the frames it never saw).
  core::Trajectory finish();

  [[nodiscard]] const SlamStatistics& statistics() const { return statistics_; }
  [[nodiscard]] const slam::Backend& backend() const { return backend_; }

 private:
  void add_keyframe(const core::RgbdFrame& keyframe, const core::SE3& odometry_pose);

  odometry::KeyframeOdometry tracker_;
  registration::PointSelector selector_;
  registration::PointCloud cloud_;
  loop_closure::LoopDetector detector_;
  slam::Backend backend_;
  core::RgbdFrame previous_;  // the last frame tracked, and its odometry pose
  core::SE3 previous_pose_;
  bool have_previous_ = false;
  SlamStatistics statistics_;
};

}  // namespace cvo::tools
