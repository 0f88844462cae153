#pragma once
// The SLAM back end (paper sections 4.3 and 6): the keyframe pose graph, every local graph, and
// the loop closures, optimised in three ways.
//
//  add_local_graph   A closed local graph of the tracker (keyframe m, frames m+1..n-1) is
//                    optimised with its keyframe fixed (local_optimisation.hpp), which gives every
//                    frame's pose relative to m. Its last frame n-1 is the next keyframe (the
//                    paper's rule), so the graph contributes the keyframe→next-keyframe edge
//                    T_m^{n-1}: the locally optimised relative pose, with the information of the
//                    graph's own keyframe→(n-1) edge (the direct registration's CVO Hessian, see
//                    edge_information.hpp). That is the choice made here rather than the marginal
//                    of n-1 propagated through the local solution: the (n-1)→n chain only adds
//                    evidence, so the direct edge's information under-states the certainty a
//                    little (conservative), and it needs no inverse of the local system.
//                    The keyframe graph's nodes are therefore the first keyframe and the last frame
//                    of every local graph: the keyframes, plus, after a tracking restart (when the
//                    new keyframe is not the closed graph's last frame) and for the final open
//                    graph, a last frame that is no keyframe (a leaf; harmless). A restart's
//                    keyframe is joined to the previous graph's last frame by a weak "bridge" edge
//                    holding the tracker's constant-velocity guess (information bridge_information
//                    times I): it keeps the graph connected and lets any loop override it.
//  add_loop          A loop T_j^i between keyframes (loop_detector.hpp) becomes a robust edge of
//                    the keyframe graph: Cauchy kernel ρ(s) = δ² log(1 + s/δ²) on s = eᵀΩe,
//                    δ = cauchy_delta (the paper's 2), so a wrong loop that disagrees with the
//                    odometry gets weight ρ'(s) = 1 / (1 + s/δ²) ≪ 1 instead of bending the map.
//                    Its information is used as it comes: the detector's CVO runs with the new
//                    keyframe (the edge's `to`) fixed, which makes its Hessian the information of
//                    this residual already (loop_verification.hpp); local edges, registered with
//                    the `from` frame fixed, need edge_information.hpp's conversion.
//                    A loop naming a keyframe the graph does not hold yet (a restart keyframe
//                    before its local graph closed) waits, and enters with that graph.
//  optimise_keyframes   Levenberg-Marquardt over the keyframe graph (posegraph/optimizer.hpp),
//                    first keyframe fixed; run after new loops. Frames follow their keyframe.
//  optimise_all      The final global optimisation: every frame a node, every local edge and
//                    bridge (plain squares), every loop (robust), first keyframe fixed, from the
//                    current poses. Its solution replaces the keyframe poses and every frame's
//                    relative pose. The paper puts the kernel on the local edges as well; here
//                    they stay plain: they are registrations the tracker accepted, their χ² are
//                    far below δ² (weight ~1 either way), and plain odometry is what lets the
//                    kernel recognise a wrong loop as the odd one out.
//
// A frame's pose is its keyframe's optimised pose ∘ its locally optimised pose relative to that
// keyframe (after optimise_all: the global solution); a keyframe-graph node's is its own.
// Frame indices are the node ids; ids increase along the run.
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/loop_closure/loop_verification.hpp"  // LoopClosure
#include "libcvo/odometry/local_graph.hpp"
#include "libcvo/posegraph/optimizer.hpp"
#include "libcvo/posegraph/pose_graph.hpp"
#include "libcvo/slam/local_optimisation.hpp"

namespace cvo::slam {

struct BackendParameters {
  double cauchy_delta = core::PoseGraphParameters{}.cauchy_delta;  // δ of the loop edges' kernel
  double bridge_information = 1.0;  // of a restart's bridge edge, per unit (σ ~ 1 m, 1 rad): a guess
  int max_iterations = 100;         // of each Levenberg-Marquardt run
};

/// A loop edge at the current poses: its χ² s = eᵀΩe and its Cauchy weight ρ'(s) = 1/(1 + s/δ²).
struct LoopState {
  loop_closure::LoopClosure loop;
  double chi2 = 0;
  double weight = 1;
};

class Backend {
 public:
  explicit Backend(const BackendParameters& parameters = {});

  /// Adds a closed local graph whose keyframe (first node) is frame `keyframe_id`; returns its
  /// local solution (valid until the next add_local_graph or optimise_all). Throws
  /// std::invalid_argument when the graph is empty, its first node is not `keyframe_id`, that
  /// keyframe's graph was added already, or the graph is malformed (local_optimisation.hpp).
  const LocalSolution& add_local_graph(posegraph::NodeId keyframe_id, const odometry::LocalGraph& graph);

  /// Adds a loop as a robust edge (or keeps it waiting, see above); true when it entered the
  /// graph now. Throws std::invalid_argument for from == to or a non-finite measurement.
  bool add_loop(const loop_closure::LoopClosure& loop);

  /// Optimises the keyframe graph; does nothing (an empty report) with fewer than two nodes.
  posegraph::OptimizationReport optimise_keyframes();
  /// The global optimisation of every frame (see above).
  posegraph::OptimizationReport optimise_all();

  /// T_world_keyframe of every node of the keyframe graph, by frame index.
  [[nodiscard]] std::map<std::int64_t, core::SE3> keyframe_poses() const;
  /// Every frame of every local graph added, in frame order, stamped with its colour timestamp.
  [[nodiscard]] core::Trajectory frame_trajectory() const;
  /// T_world_odometry: the correction that maps the tracker's latest poses into the back end's
  /// world, from the last frame of the latest local graph; the identity before any graph.
  [[nodiscard]] core::SE3 odometry_correction() const;

  /// Loops in the graph with their χ² and Cauchy weight at the current poses, in insertion order.
  [[nodiscard]] std::vector<LoopState> loops() const;
  /// Loops still waiting for a keyframe.
  [[nodiscard]] std::size_t pending_loops() const { return pending_.size(); }
  /// Loops that entered the graph since the last optimise_keyframes() or optimise_all().
  [[nodiscard]] std::size_t unoptimised_loops() const { return unoptimised_loops_; }

  [[nodiscard]] const posegraph::PoseGraph& keyframe_graph() const { return keyframes_; }
  [[nodiscard]] std::size_t local_graphs() const { return graphs_.size(); }
  /// Increases whenever a pose keyframe_poses() or frame_trajectory() returns may have changed.
  [[nodiscard]] std::uint64_t revision() const { return revision_; }
  [[nodiscard]] const BackendParameters& parameters() const { return parameters_; }

 private:
  struct StoredGraph {
    posegraph::NodeId keyframe = 0;
    LocalSolution solution;
  };
  struct StoredLoop {
    loop_closure::LoopClosure loop;
    posegraph::Edge edge;
  };

  [[nodiscard]] posegraph::OptimizerOptions optimizer_options() const;
  [[nodiscard]] std::map<posegraph::NodeId, core::StampedPose> frame_poses() const;
  void join_keyframe(posegraph::NodeId keyframe, const LocalFrame& first);
  bool insert_loop(const loop_closure::LoopClosure& loop);

  BackendParameters parameters_;
  posegraph::PoseGraph keyframes_;
  posegraph::Optimizer optimizer_;  // keeps the keyframe graph's symbolic analysis between runs
  std::vector<StoredGraph> graphs_;
  std::map<posegraph::NodeId, std::size_t> graph_of_keyframe_;
  std::vector<posegraph::Edge> bridges_;
  std::vector<StoredLoop> loops_;
  std::vector<loop_closure::LoopClosure> pending_;
  std::size_t unoptimised_loops_ = 0;
  std::optional<posegraph::NodeId> last_node_;  // last frame of the latest graph
  core::SE3 last_odometry_;                    // its tracker pose
  std::uint64_t revision_ = 0;
};

}  // namespace cvo::slam
