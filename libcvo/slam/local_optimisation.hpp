#pragma once
// Optimisation of one closed local graph with its keyframe held fixed (paper section 6, first
// step): over the poses P of the graph's frames,
//   min_P  Σ_(i,j) e_ijᵀ Ω_ij e_ij,   e_ij = log(T_ij⁻¹ P_i⁻¹ P_j),
// the keyframe→frame edges T_m^n and the (n-1)→n edges T_{n-1}^n of the tracker
// (odometry/local_graph.hpp), Ω the CVO Hessians in the residual's coordinates
// (edge_information.hpp). Plain squares: these edges come from registrations the tracker accepted.
//
// The poses are solved relative to the keyframe (its pose the identity), so the result does not
// depend on where the keyframe sits in the world: the back end places it. The tracker's poses,
// re-expressed relative to the keyframe, are the initial guess.
#include <vector>

#include "libcvo/core/se3.hpp"
#include "libcvo/odometry/local_graph.hpp"
#include "libcvo/posegraph/optimizer.hpp"
#include "libcvo/posegraph/pose_graph.hpp"

namespace cvo::slam {

struct LocalFrame {
  posegraph::NodeId id = 0;  // the frame index
  double timestamp = 0;
  core::SE3 relative;  // T_keyframe_frame, locally optimised (identity for the keyframe)
  core::SE3 odometry;  // T_world_frame as the tracker published it
};

struct LocalSolution {
  std::vector<LocalFrame> frames;      // in the graph's order: frames.front() is the keyframe
  std::vector<posegraph::Edge> edges;  // the graph's edges, information as Ω above
  posegraph::OptimizationReport report;
};

/// Throws std::invalid_argument for an empty graph, a repeated frame, a non-finite pose, or an
/// edge that names a frame the graph does not hold.
LocalSolution optimise_local_graph(const odometry::LocalGraph& graph, const posegraph::OptimizerOptions& options = {});

}  // namespace cvo::slam
