#pragma once
// Every tunable of the method, grouped as the paper groups them. Defaults are the paper's
// Table 1 (tab:parameters) where it gives a value; the others are marked with where they come from.
// These are plain values: libcvo/config reads them from YAML, each library takes the group it needs.
#include <cstddef>

namespace cvo::core {

/// Point selection (paper section 3, DSO-style semi-dense selection).
struct SelectionParameters {
  std::size_t target_points = 3000;  // per 640x480 frame (paper section 6)
  double min_depth_m = 0.1;          // valid depth range
  double max_depth_m = 5.0;
};

/// The RKHS inner product and the CVO solver (paper section 3, eq. 5-6; Table 1).
struct CvoParameters {
  double ell_init = 0.1;                     // spatial kernel initial length-scale ℓ_init (m)
  double ell_min = 0.05;                     // smallest length-scale of the schedule (m)
  double ell_decay = 0.9;                    // factor applied to ℓ as it converges
  double sigma = 0.1;                        // spatial kernel signal variance σ
  double ell_color = 0.1;                    // colour kernel length-scale ℓ_c
  double sigma_color = 1.0;                  // colour kernel signal variance σ_c
  double sparsification_threshold = 8.315e-3;  // a pair whose kernel product is below this is dropped
  int max_iterations = 100;
  double min_step = 1e-5;                    // convergence: |Δξ| below this at ℓ_min
  std::size_t max_neighbours = 64;           // per point, fixed memory capacity
  int threads = 1;                           // the tracker runs single-threaded by default
};

/// Keyframe selection (paper section 4, eq. 9-10; Table 1).
struct KeyframeParameters {
  double inner_product_ratio_threshold = 0.7;  // γ_thres
  double translation_threshold_m = 0.15;       // t_thres
  double rotation_threshold_deg = 30.0;        // θ_thres
};

/// Loop closure (paper section 5; Table 1).
struct LoopClosureParameters {
  double similarity_threshold = 0.3;  // η_thres, normalised bag-of-words score
  double match_ratio = 0.7;           // best / second-best descriptor distance
  int min_matches = 5;
};

/// Robust pose graph (paper section 5; Table 1).
struct PoseGraphParameters {
  double cauchy_delta = 2.0;  // δ of ρ(x) = δ² log(1 + x/δ²)
};

/// Reading TUM-layout recordings.
struct DatasetParameters {
  double max_association_dt = 0.02;  // s, colour-depth timestamp association (TUM's default)
};

}  // namespace cvo::core
