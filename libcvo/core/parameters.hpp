#pragma once
// Every tunable of the method, grouped as the paper groups them. Defaults are the paper's
// Table 1 (tab:parameters) where it gives a value; the others are marked with where they come from.
// How the tuned values were chosen, with the measurements: bench/odometry-tuning.md.
//
// The rule: a tunable lives in two places, its field here (its default and its why) and its row
// in the configuration's table (libcvo/config/config.cpp: its key, range and doc). Modules take
// these structs whole (odometry::KeyframeOdometryParameters holds a KeyframeTrackingParameters,
// not copies of its fields), so libcvo/config/module_parameters.cpp copies structs, not fields,
// and no module re-declares a tunable or its default. tests/config/module_parameters_test.cpp
// holds every module's parameter struct to it, member by member.
//
// These are plain values: libcvo/config reads them from YAML (one section per struct, or two
// structs sharing one section where noted); equality is member by member, doubles exactly.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

namespace cvo::core {

/// Point selection (paper section 3, DSO-style semi-dense selection).
struct SelectionParameters {
  std::size_t target_points = 3000;  // per 640x480 frame (paper section 6)
  double min_depth_m = 0.1;          // valid depth range
  double max_depth_m = 5.0;
  // Scale of the gradient part of each point's label (0: RGB only). The label's gradient is a central
  // difference of [0, 1] intensities, spanning [-1, 1]; halved it is the derivative per pixel, which
  // spans 1 as each colour channel does, so the one colour length-scale ℓ_c weighs every dimension alike.
  double gradient_weight = 0.5;
  // Depth-time compensation (KF-CVO). A point's depth is read where its colour pixel's ray was when
  // the depth image was taken, at the last measured velocity, and moved back to the colour image's
  // time. The depth image is taken at its stamp plus this offset, relative to the colour stamps:
  // -10 ms, a timing property of the Kinect v1 / OpenNI recordings of TUM, whose depth stamps are
  // late (the depth image is computed on the sensor after its exposure).
  // Frames whose two stamps are equal (rendered frames, synchronised sensors) are taken as
  // simultaneous and left as they are.
  double depth_time_offset_s = -0.010;
  // Each point's depth is the mean of the valid depths in the (2r+1)² pixels around where it is
  // read, r = depth_window, that lie within depth_window_tolerance · z of that pixel's own depth
  // (the same surface: a depth edge's other side is left out). A depth sensor's per-pixel noise
  // and quantisation then enter a point by a fraction of their size, as they would across the
  // dense pixels of a direct method. 0: the pixel's own depth. The tolerance passes a structured-
  // light sensor's noise and a disparity step or two (Kinect v1: 0.3 % of z per metre) and a
  // surface seen at 60° over two pixels, and stops at the few-centimetre steps of an object on a
  // table, which a looser one blurs into the point (figures: bench/odometry-tuning.md).
  int depth_window = 2;
  double depth_window_tolerance = 0.01;

  bool operator==(const SelectionParameters&) const = default;
};

/// The RKHS inner product and the CVO solver (paper section 3, eq. 5-6; Table 1).
///
/// Reading of Table 1: σ and σ_c are taken literally as the kernels' standard deviations, so a
/// pair's weight is
///   a_ij = σ² σ_c² exp(-|x_i - T z_j|² / 2ℓ²) exp(-|ℓ_X(x_i) - ℓ_Z(z_j)|² / 2ℓ_c²)
/// and it counts when a_ij ≥ the sparsification threshold, i.e. when the two normalised kernels'
/// product exceeds 0.83. Few pairs contribute, yet with the Gauss-Newton step this registers as
/// accurately as the looser "σ is a variance" reading at a fraction of the cost (measured:
/// libcvo/registration/README.md). Colour labels are RGB in [0, 1] plus the grey gradient in
/// [-1, 1] (registration/feature.hpp).
struct CvoParameters {
  double ell_init = 0.1;  // ℓ_init: spatial kernel initial length-scale (m)
  // Smallest length-scale of the schedule (m); not in Table 1: one decay step below ℓ_init (0.1 ->
  // 0.07). A further step (0.05) resolves textured frames' rotation a little better, but where the
  // pairs come from structure alone (texture-less scenes) a narrower kernel keeps too few of them.
  double ell_min = 0.07;
  double ell_decay = 0.7;                      // ℓ <- ℓ · decay each time the step has converged
  double sigma = 0.1;                          // σ: spatial kernel signal (standard deviation)
  double ell_color = 0.1;                      // ℓ_c: colour kernel length-scale
  double sigma_color = 1.0;                    // σ_c: colour kernel signal (standard deviation)
  double sparsification_threshold = 8.315e-3;  // pairs with a_ij below this contribute nothing
  int max_iterations = 100;
  double min_step = 1e-4;         // converged at ℓ_min when |Δρ| + |Δφ| < this (m + rad)
  int threads = 1;                // the tracker runs single-threaded by default
  bool mutual_visibility = true;  // align() sums only what both views see (registration.hpp)

  bool operator==(const CvoParameters&) const = default;
};

/// What every tracker keeps besides the paper's values (libcvo/odometry); YAML section `odometry`.
struct OdometryParameters {
  // Capacity of each point cloud (the trackers', and the loop detector's stored keyframe clouds):
  // fixed memory. Selection keeps about target_points; more than this is clamped.
  std::size_t max_points = 8192;
  // Frame-to-frame trackers (cvo, opencv-*): failed registrations in a row against one reference
  // after which the failed frame becomes the reference (frame_to_frame.hpp). Not from the paper.
  int restart_after_failures = 3;

  bool operator==(const OdometryParameters&) const = default;
};

/// Keyframe selection (paper section 4, eq. 9-10; Table 1).
struct KeyframeParameters {
  double inner_product_ratio_threshold = 0.7;  // γ_thres
  double translation_threshold_m = 0.15;       // t_thres
  double rotation_threshold_deg = 30.0;        // θ_thres

  bool operator==(const KeyframeParameters&) const = default;
};

/// KF-CVO's own settings beyond Table 1 (libcvo/odometry/keyframe_odometry.hpp has the maths);
/// YAML section `keyframe`, after the paper's thresholds.
struct KeyframeTrackingParameters {
  std::size_t local_graph_capacity = 300;  // frames per keyframe before one is forced (10 s at 30 Hz)
  // The inner products of γ (eq. 9) use their own, looser spatial kernel: with the tracker's tight
  // one (σ = 0.1) γ, a ratio of two sums, rests on a few hundred pairs and jumps from frame to frame
  // (spurious keyframes). σ = 0.316 is Table 1's "signal variance" 0.1 read as a variance (σ² = 0.1):
  // pairs count from a normalised kernel product of about 0.083, γ sums ~10^5 of them and is smooth.
  double gamma_ell = 0.1;      // length-scale of γ's inner products (m)
  double gamma_sigma = 0.316;  // spatial signal of γ's inner products (std. dev.)
  // γ is a ratio of two such sums over the same kind of cloud: every stride-th point of the frame
  // estimates it as well as all of them (~10^5 pairs in all), at 1/stride of the cost.
  std::size_t gamma_stride = 4;
  // Fusion of the keyframe result with the chain: the chain edge's information is scaled by
  // chain_weight, ramped as (θ / chain_full_weight_deg)² up to it (θ: rotation from the keyframe).
  // 1 weighs both edges by their CVO Hessians, the paper's local graph; the chain is no more certain
  // than its Hessian says (it also carries frame n-1's own error). Near the keyframe the keyframe
  // edge alone drifts least, so the chain comes in as the rotation grows; the ramp reaches full weight
  // early, as keyframe-to-frame registrations of a few dozen kernel pairs jitter on real sensors.
  double chain_weight = 1.0;           // 0: the keyframe edge alone
  double chain_full_weight_deg = 3.0;  // 0: full weight at every rotation
  // The fastest turn the camera may already make at a session's first pair, when no motion is known
  // yet: that pair's registration starts with a kernel wide enough to reach the pairs such a turn
  // moves over one frame interval (keyframe_odometry.hpp). A property of the robot, not a fit: the
  // default is 1.5 times fr1/rpy's measured peak (158 deg/s), issue 47's stated envelope.
  double max_turn_rate_deg_s = 240.0;

  bool operator==(const KeyframeTrackingParameters&) const = default;
};

/// Loop closure (paper section 5; Table 1).
struct LoopClosureParameters {
  double similarity_threshold = 0.3;  // η_thres, normalised bag-of-words score
  double match_ratio = 0.7;           // best / second-best descriptor distance
  int min_matches = 5;

  bool operator==(const LoopClosureParameters&) const = default;
};

/// Loop verification beyond Table 1 (libcvo/loop_closure/loop_verification.hpp has the steps);
/// YAML section `loop_closure`, after the paper's values.
struct LoopVerificationParameters {
  // CVO refinements per new keyframe, best η first (0: no limit): CVO is the back end's main cost,
  // and verifying only the best few kept the map as good.
  int max_refinements = 3;
  int ransac_iterations = 300;        // minimal sets tried for the initial pose
  double ransac_inlier_m = 0.03;      // 3-D distance for a match to count as an inlier (m)
  int min_inliers = 12;               // fewer after RANSAC: no initial pose, no loop
  double min_inlier_retention = 0.5;  // share of RANSAC's inliers the CVO pose must keep (step 3b)
  std::uint32_t ransac_seed = 0;      // RANSAC's std::mt19937: the same loops every run
  // ORB keypoints (cv::ORB; loop_closure/orb_features.hpp): ORB-SLAM2's feature count, OpenCV's
  // other defaults. The installed vocabulary was trained with these (cvo-vocabulary).
  int orb_features = 1000;        // at most this many keypoints, the strongest first
  double orb_scale_factor = 1.2;  // pyramid scale between levels
  int orb_levels = 8;             // pyramid levels
  int orb_edge_threshold = 31;    // border without features, pixels (>= patch size: descriptors fit)
  int orb_fast_threshold = 20;    // FAST intensity threshold

  bool operator==(const LoopVerificationParameters&) const = default;
};

/// Robust pose graph (paper section 5; Table 1) and the back end's optimisation (libcvo/slam/backend.hpp).
struct PoseGraphParameters {
  double cauchy_delta = 2.0;  // δ of ρ(x) = δ² log(1 + x/δ²)
  // Information (times I) of the bridge edge joining a tracking restart's keyframe to the previous
  // local graph, per unit (σ ~ 1 m, 1 rad): a guess, weak so that any loop overrides it.
  double bridge_information = 1.0;
  int max_iterations = 100;  // of each Levenberg-Marquardt run

  bool operator==(const PoseGraphParameters&) const = default;
};

/// Reading TUM-layout recordings.
struct DatasetParameters {
  double max_association_dt = 0.02;  // s, colour-depth timestamp association (TUM's default)

  bool operator==(const DatasetParameters&) const = default;
};

/// A rigid pose as the configuration gives it: x y z (m), qx qy qz qw (unit quaternion).
using PoseParameter = std::array<double, 7>;

/// The map a robot navigates by (libcvo/mapping): every keyframe's local map, placed at its pose.
/// Defaults are a ground robot's (Nav2's usual 5 cm costmap cells; obstacles from above a
/// doorsill to above a person's head); the occupancy probabilities are OctoMap's defaults.
struct MappingParameters {
  double cell_size = 0.05;            // m: grid cells and OctoMap voxels
  double voxel_size = 0.02;           // m: the coloured cloud's voxels
  double obstacle_min_height = 0.10;  // m above the floor: lower points are floor, seen free
  double obstacle_max_height = 1.80;  // m above the floor: higher points are no obstacle
  // m: depth beyond this is not mapped; a Kinect-class sensor's depth error grows with z² (about
  // 4 cm at 4 m), as large as a cell.
  double max_range = 4.0;
  int pixel_stride = 2;           // every stride-th pixel of each row and column is mapped
  double hit_probability = 0.7;   // a keyframe that sees a surface in a cell (OctoMap: 0.7)
  double miss_probability = 0.4;  // a keyframe whose rays cross a cell (OctoMap: 0.4)
  // The camera's pose on a base whose z is up and whose origin is on the floor (a robot's
  // base_link): when given, it says which way is up and where the floor is.
  std::optional<PoseParameter> base_T_camera;

  bool operator==(const MappingParameters&) const = default;
};

/// Localization in a stored map (slam::Mapper::localize_only): a session being localized keeps
/// only its newest keyframes in memory, so a robot can run in a map for months in fixed memory.
/// The window spans a few seconds of keyframes: enough for the window's own odometry to carry a
/// verified match forward, short enough that its drift stays small.
struct LocalizationParameters {
  std::size_t window_keyframes = 16;  // a localizing session's keyframes kept, the newest

  bool operator==(const LocalizationParameters&) const = default;
};

}  // namespace cvo::core
