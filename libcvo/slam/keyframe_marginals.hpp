#pragma once
// The marginal covariances of a few keyframe-graph nodes (each session's newest keyframe, and the
// last node of its latest local graph, which the next graph hangs from): what CVO_MAP and
// CVO_MAP_CORRECTION report of each session, kept without factorising the whole graph per update.
//
// posegraph::marginal_covariances factorises H = Σ w Jᵀ Ω J of the whole graph: O(N) per call, so
// O(N²) over a run when asked after every keyframe. But a tracker's keyframe graph mostly grows by
// leaves: a closed local graph adds its last frame n as a new node held by one edge from the
// keyframe m before it (measurement Z = T_m^n, information Ω), at the pose T_m · Z, and moves
// nothing. A leaf leaves every other marginal as it was (the Schur complement of its block is the
// old H), and its own, in the same Laplace approximation (e = J_m δ_m + J_n δ_n with e ~ N(0, Ω⁻¹)
// independent of δ_m ~ N(0, Σ_m); J_m, J_n the edge's Jacobians at the current poses, residual.hpp),
// is exactly
//     Σ_n = J_n⁻¹ (Ω⁻¹ + J_m Σ_m J_mᵀ) J_n⁻ᵀ,
// which at the leaf's zero residual (J_n = I, J_m = -Ad(Z⁻¹)) is Σ_n = Ad(Z⁻¹) Σ_m Ad(Z⁻¹)ᵀ + Ω⁻¹:
// the previous marginal carried along the edge, plus the edge's own uncertainty (Σ_m = 0 for a fixed
// m, a piece's anchor). The same holds with the leaf at the edge's `from` end (J_m, J_n swapped).
//
// So follow() extends the cache by each new leaf whose neighbour it holds (O(1) per new node); a
// growth of any other shape (a loop or any robust edge, an edge between nodes seen before, a new
// node held by no edge or by a fixed one, a leaf whose neighbour's marginal is not held, an Ω that
// is not positive definite) empties it, and so does invalidate() (moved poses: an optimisation).
// Then the next compute() factorises the whole graph once, for every node it is asked for.
#include <cstddef>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "libcvo/core/se3.hpp"
#include "libcvo/posegraph/optimizer.hpp"
#include "libcvo/posegraph/pose_graph.hpp"

namespace cvo::slam {

class KeyframeMarginals {
 public:
  /// The graph grew since the marginals were last computed or followed: new leaves extend them,
  /// anything else empties them (see the header).
  void follow(const posegraph::PoseGraph& graph);
  /// Poses moved (or the graph changed otherwise): nothing held is valid any more.
  void invalidate();
  /// One factorisation of `graph` for `nodes` (each in the graph); what it gives replaces what was
  /// held. When it fails (a free node no edge holds) nothing is held, and it is not tried again
  /// before the graph changes.
  void compute(const posegraph::PoseGraph& graph, const std::vector<posegraph::NodeId>& nodes,
               const posegraph::OptimizerOptions& options);
  /// Keeps only the marginals of `nodes` (the ones asked for, and those the next leaves hang from).
  void keep(const std::vector<posegraph::NodeId>& nodes);

  [[nodiscard]] std::optional<core::Matrix6d> find(posegraph::NodeId node) const;
  /// Whether a compute() now could give more than find() does (false after a failed one, until the
  /// graph changes).
  [[nodiscard]] bool worth_computing() const { return !failed_; }
  /// Factorisations so far (what follow() saves).
  [[nodiscard]] std::size_t factorisations() const { return factorisations_; }

 private:
  bool extend(const posegraph::PoseGraph& graph, const posegraph::Edge& edge);

  bool valid_ = false;  // known_ and seen_ describe the graph with edges_seen_ edges
  bool failed_ = false;
  std::unordered_map<posegraph::NodeId, core::Matrix6d> known_;
  std::unordered_set<posegraph::NodeId> seen_;  // every node of the graph when last computed or followed
  std::size_t edges_seen_ = 0;
  std::size_t factorisations_ = 0;
};

}  // namespace cvo::slam
