#pragma once
// Incremental Gauss-Newton for a pose graph that grows (iSAM2's idea on CHOLMOD's Modify module):
// a new loop costs what the part of the factor it changes costs, not the whole graph.
//
// State. Every free node k has a linearisation point θ_k and a step Δ_k; its estimate is
// θ_k (+) Δ_k (residual.hpp's retraction). Each edge is linearised at the θ of its two nodes: with
// S the square root of its weighted information (SᵀS = w Ω, w the Cauchy weight ρ'(χ²) of a robust
// edge at θ, 1 otherwise) and J = [J_i J_j] its Jacobian, it contributes
//   H += (S J)ᵀ (S J),   g += (S J)ᵀ (S e).
// The optimiser keeps a simplicial LDLᵀ factor of P H Pᵀ (P a fill-reducing block ordering) and
// Δ = -H⁻¹ g, so the estimate is one Gauss-Newton step from θ.
//
// update():
//  - new nodes take blocks reserved at the end of the ordering. A reserved block stands in H as the
//    identity (L's column the identity too, Δ = 0); once its node has an edge in H the identity is
//    removed by a rank-6 downdate.
//  - relinearisation (fluid, as iSAM2): a node whose |Δ_k|∞ exceeds the threshold moves its θ_k to
//    its estimate; every edge touching it is relinearised by a rank-6 update with its new (S J)
//    and then a downdate with its old one (update first: the intermediate H stays positive
//    definite); its Cauchy weight is recomputed then, which is the IRLS re-weighting.
//  - each new edge enters by a rank-6 update with its (S J)ᵀ: cholmod_updown modifies only the
//    columns on the elimination-tree path from the edge's first column to the root, so a loop
//    between recent nodes (their blocks are last in the ordering) touches few columns.
//  - Δ is solved again, a full forward and back substitution: O(nnz(L)), no factorisation, and
//    cheap next to one (a factorisation of a pose graph costs tens to thousands of times nnz(L)).
// When the part to relinearise is large (more than `rebuild_fraction` of the free nodes, or rank
// updates along its paths that would cost more flops than one factorisation: a large correction), when the reserved
// blocks run out, when updates have grown nnz(L) per block past `fill_growth` times its value after the last analysis,
// or after set_pose / set_fixed, the factor is rebuilt: every node relinearised at its estimate, a new ordering, one
// numeric factorisation (a batch Gauss-Newton step; should round-off make an ill-conditioned H not positive definite, H
// + μ diag(H) as Levenberg-Marquardt, μ from 1e-9: same fixed point). The ordering is CAMD on the 6x6-block pattern
// with the newest nodes constrained last (the next edges arrive there, so their paths stay short, as iSAM2's
// constrained COLAMD), then the reserved blocks, kept as given (no postorder); the capacity is twice the free nodes, so
// rebuilds for capacity happen a logarithmic number of times.
//
// Convergence: an update() without new edges relinearises every node whose step exceeds
// `converged_threshold`, so repeated updates are Gauss-Newton iterations and reach the batch
// optimum (the tests: the shared graphs fed edge by edge).
//
// Gauge: fixed nodes are held (no variables); when no node is fixed the first node added is held,
// as Optimizer holds the first node of a graph without a fixed one.
#include <cstddef>
#include <functional>
#include <memory>
#include <unordered_map>
#include <vector>

#include "libcvo/core/parameters.hpp"
#include "libcvo/posegraph/cost.hpp"
#include "libcvo/posegraph/pose_graph.hpp"

namespace cvo::posegraph {

namespace detail {
struct Cholmod;
}  // namespace detail
}  // namespace cvo::posegraph
struct cholmod_sparse_struct;
namespace cvo::posegraph {

struct IncrementalOptions {
  core::PoseGraphParameters pose_graph{};  // its cauchy_delta, for the edges marked robust
  double relinearise_threshold = 1e-2;     // |Δ_k|∞ (m, rad) beyond which node k is relinearised
  double converged_threshold = 1e-9;       // the same in an update() without new edges
  double rebuild_fraction = 0.25;          // relinearising more free nodes than this fraction: rebuild
  bool rebuild_when_cheaper = true;        // also rebuild when the rank updates would cost more flops
  double fill_growth = 2.0;                // nnz(L) per block past this multiple of the last analysis': rebuild
  std::size_t initial_capacity = 64;       // node blocks of the first analysis
  std::size_t newest_last = 16;            // newest nodes the ordering keeps last (CAMD constraint)
};

struct UpdateReport {
  std::size_t new_edges = 0;
  std::size_t relinearised_nodes = 0;
  std::size_t touched_columns = 0;       // factor columns an updown modified (a rebuild: all of them)
  bool rebuilt = false;                  // a fresh analysis and factorisation
  const char* rebuild_reason = nullptr;  // why: "structure changed", "capacity", "large correction", "fill", ...
  double max_step = 0;                   // max |Δ_k|∞ after the update
};

class IncrementalOptimizer {
 public:
  explicit IncrementalOptimizer(IncrementalOptions options = {});
  ~IncrementalOptimizer();
  IncrementalOptimizer(IncrementalOptimizer&&) noexcept;
  IncrementalOptimizer& operator=(IncrementalOptimizer&&) noexcept;
  IncrementalOptimizer(const IncrementalOptimizer&) = delete;
  IncrementalOptimizer& operator=(const IncrementalOptimizer&) = delete;

  /// As PoseGraph::add_node; the node enters the system at the next update().
  void add_node(NodeId id, const core::SE3& pose, bool fixed = false);
  /// As PoseGraph::add_edge (same checks); enters at the next update().
  void add_edge(const Edge& edge);
  /// Moves a node (its estimate becomes `pose`) or holds / frees it: the next update() rebuilds.
  void set_pose(NodeId id, const core::SE3& pose);
  void set_fixed(NodeId id, bool fixed);

  UpdateReport update();
  /// update() with this relinearisation threshold whatever the new edges.
  UpdateReport update(double relinearise_threshold);

  [[nodiscard]] bool contains(NodeId id) const { return index_.contains(id); }
  [[nodiscard]] core::SE3 pose(NodeId id) const;  // the estimate θ (+) Δ
  [[nodiscard]] bool fixed(NodeId id) const;
  /// The graph at the estimates (edges in insertion order).
  [[nodiscard]] PoseGraph graph() const;
  /// F = 1/2 Σ ρ(χ²) at the estimates: O(edges), for callers and tests, not used by update().
  [[nodiscard]] double cost() const;
  [[nodiscard]] std::size_t nodes() const { return nodes_.size(); }
  [[nodiscard]] std::size_t factor_columns() const;  // the factor's dimension, reserved blocks included
  [[nodiscard]] int rebuilds() const { return rebuilds_; }

 private:
  struct NodeState {
    NodeId id = 0;
    core::SE3 theta;  // linearisation point
    core::Vector6d delta = core::Vector6d::Zero();
    bool fixed = false;
    bool held = false;    // fixed, or the gauge
    int block = -1;       // block column of H (before the ordering); -1 while unassigned / held
    bool active = false;  // its reserved identity has been removed
    std::vector<std::size_t> edges;
  };
  struct EdgeState {
    Edge edge;
    std::size_t i = 0, j = 0;                                                // node indices
    Eigen::Matrix<double, 6, 12> sj = Eigen::Matrix<double, 6, 12>::Zero();  // S [J_i J_j] at θ
    core::Vector6d se = core::Vector6d::Zero();                              // S e at θ
    bool factored = false;
  };

  using Rows = std::vector<std::pair<long, int>>;  // factor row, column of the block being added

  [[nodiscard]] const NodeState& node_state(NodeId id) const;
  void linearise(EdgeState& edge);
  void add_to_gradient(const EdgeState& edge, double sign);
  std::size_t updown(bool update, const EdgeState& edge);
  std::size_t updown(bool update, const Rows& rows, const std::function<double(int, int)>& value);
  std::size_t remove_identity(NodeState& node);
  std::size_t mark_path(long first);
  bool assign_blocks();
  std::vector<long> block_ordering();
  void assemble();  // H into the Cholmod bundle's matrix, g into gradient_
  void rebuild(UpdateReport& report);
  void factorize_damped(cholmod_sparse_struct* H);
  void solve(UpdateReport& report);
  [[nodiscard]] std::vector<std::size_t> to_relinearise(double threshold) const;
  void relinearise(const std::vector<std::size_t>& moved, UpdateReport& report);
  [[nodiscard]] std::vector<std::size_t> edges_of(const std::vector<std::size_t>& moved) const;
  [[nodiscard]] bool cheaper_to_rebuild(const std::vector<std::size_t>& edges) const;
  [[nodiscard]] std::size_t factor_nonzeros() const;
  [[nodiscard]] bool fill_grown() const;

  IncrementalOptions options_;
  RobustKernel kernel_;
  PoseGraph graph_;  // the nodes and edges as added (their checks; poses are the initial guesses)
  std::unique_ptr<detail::Cholmod> cholmod_;
  std::vector<NodeState> nodes_;
  std::unordered_map<NodeId, std::size_t> index_;
  std::vector<EdgeState> edges_;
  std::size_t first_new_edge_ = 0;
  std::size_t capacity_ = 0;           // node blocks in the factor
  std::size_t used_blocks_ = 0;        // blocks assigned so far
  std::vector<long> position_;         // inverse permutation: H column → factor column
  Eigen::VectorXd gradient_;           // g, in H's columns
  std::size_t analysed_nonzeros_ = 0;  // nnz(L) of the blocks in use after the last analysis
  std::size_t analysed_blocks_ = 0;
  double factor_flops_ = 0;  // of one numeric factorisation, from the last analysis
  std::vector<char> marks_;  // factor columns counted in this update
  std::vector<long> marked_;
  bool must_rebuild_ = true;
  int rebuilds_ = 0;
};

}  // namespace cvo::posegraph
