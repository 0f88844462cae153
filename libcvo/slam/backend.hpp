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
//  optimise_keyframes   Incremental Gauss-Newton over the keyframe graph
//                    (posegraph/incremental_optimizer.hpp), each piece's anchor fixed; run after new
//                    loops. The keyframe graph's new nodes and edges (keyframes, bridges, loops) are
//                    added to the incremental optimiser as they came, so a loop costs what the part of
//                    the factor it changes costs; the updates repeat until no node moves by more than
//                    the relinearisation threshold (at most max_iterations). A rigid move of a piece
//                    (a join, below) or a released anchor makes the next one a rebuild (the whole
//                    graph, once). Frames follow their keyframe. A merge (below) changes the graph's
//                    structure, which factors cannot follow: the optimiser keeps the merged keyframe's
//                    factors on its own node, tied to the covering keyframe (10^4 times the loop's
//                    information: rigid, as the keyframe graph holds it), every fused edge's new
//                    contribution as a factor of its own
//                    (to first order the same cost); it is built anew from the keyframe graph once it
//                    holds twice the graph's edges, or after a join (sync_incremental).
//  optimise_all      The final global optimisation: every frame a node, every local edge and
//                    bridge (plain squares), every loop (robust), first keyframe fixed, from the
//                    current poses. Its solution replaces the keyframe poses and every frame's
//                    relative pose. The paper puts the kernel on the local edges as well; here
//                    they stay plain: they are registrations the tracker accepted, their χ² are
//                    far below δ² (weight ~1 either way), and plain odometry is what lets the
//                    kernel recognise a wrong loop as the odd one out.
//
// Sessions (several tracker runs, slam/mapper.hpp): every local graph belongs to a session, and
// the restart bridge above only joins graphs of one session. A session's first keyframe starts a
// piece of map of its own, anchored (fixed) at its odometry pose; the first session's piece is the
// map. A loop between two pieces joins them: the piece whose first session came later is moved
// rigidly so that the loop holds exactly, its anchor is released, and from then on it is one
// piece (the map, when either was). Every optimisation holds each piece's anchor, so pieces that
// share no loop stay well-posed side by side.
//
// Merged keyframes (backend_merge.cpp, keyframe_merge.hpp has the algebra; slam/mapper.hpp decides
// when): merge_keyframe(k, c, T) takes keyframe k out of the keyframe graph; it is an alias of c
// with X_k = X_c · T from then on. Its edges, and every later edge naming it (a local graph that
// starts or ends at k, a restart's bridge, a loop), are re-expressed as edges of c, and an edge
// between two nodes that already have one (same kind: plain or robust) is fused into it, so the
// keyframe graph grows with the area a revisit covers, not with the time spent there. The final
// global optimisation has every frame as a node, k included: there k is held to c by a robust edge
// with the loop's information, and T follows its solution.
//
// Settling (backend_settle.cpp; a service that lives for months calls it, through
// Mapper::settle): the local graph of a merged keyframe k adds nothing to the keyframe graph once
// it is in (its edge was moved onto c and fused), only frames to the global optimisation, which
// grow with the time spent. settle(k) forgets those frames and keeps the graph's keyframe edge,
// resolved onto the covering keyframes and fused per pair, as a settled edge of the global
// optimisation (the keyframe graph's edges are those very contributions fused with the rest); a
// merged keyframe that no kept graph, bridge or session names any more is forgotten with its
// loops (their edges settled as well). What stays grows with the area: the keyframe graph, the
// settled edges between its nodes, the frames of unmerged keyframes' graphs. frame_trajectory()
// leaves settled frames out.
//
// A frame's pose is its keyframe's optimised pose ∘ its locally optimised pose relative to that
// keyframe (after optimise_all: the global solution); a keyframe-graph node's is its own. Node ids
// are the caller's (the mapper's per-session frame numbering); within a session they increase along
// the run.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/loop_closure/loop_verification.hpp"  // LoopClosure
#include "libcvo/odometry/local_graph.hpp"
#include "libcvo/posegraph/incremental_optimizer.hpp"
#include "libcvo/posegraph/optimizer.hpp"
#include "libcvo/posegraph/pose_graph.hpp"
#include "libcvo/slam/keyframe_merge.hpp"
#include "libcvo/slam/local_optimisation.hpp"

namespace cvo::slam {

/// The pose graph's core struct whole: cauchy_delta (δ of the loop edges' kernel), bridge_information
/// (of a restart's bridge edge) and max_iterations (of each Levenberg-Marquardt run). From the
/// configuration: config::backend_parameters (libcvo/config/module_parameters.hpp).
using BackendParameters = core::PoseGraphParameters;

/// A loop edge at the current poses: its χ² s = eᵀΩe and its Cauchy weight ρ'(s) = 1/(1 + s/δ²).
struct LoopState {
  loop_closure::LoopClosure loop;
  double chi2 = 0;
  double weight = 1;
};

class Backend {
 public:
  explicit Backend(const BackendParameters& parameters = {});

  /// Registers a session (nothing when known); the first one registered defines the map frame.
  /// add_local_graph registers its session itself.
  void add_session(core::SessionId session);

  /// Adds a closed local graph of `session` whose keyframe (first node) is node `keyframe_id`;
  /// returns its local solution (valid until the next add_local_graph or optimise_all). Throws
  /// std::invalid_argument when the graph is empty, its first node is not `keyframe_id`, that
  /// keyframe's graph was added already, a node belongs to another session, the graph is
  /// malformed (local_optimisation.hpp), or an information matrix is one
  /// core::check_information refuses.
  const LocalSolution& add_local_graph(core::SessionId session, posegraph::NodeId keyframe_id,
                                       const odometry::LocalGraph& graph);
  /// One session (the first registered, else 0).
  const LocalSolution& add_local_graph(posegraph::NodeId keyframe_id, const odometry::LocalGraph& graph);

  /// Adds a loop as a robust edge (or keeps it waiting, see above); true when it entered the
  /// graph now. Throws std::invalid_argument for from == to, a non-finite measurement or an
  /// information matrix core::check_information refuses.
  bool add_loop(const loop_closure::LoopClosure& loop);

  /// Optimises the keyframe graph incrementally; does nothing (an empty report) with fewer than two
  /// nodes. The report's iterations are the updates, factorizations the rebuilds among them,
  /// converged whether the last update relinearised no node; its costs are not evaluated (0: that
  /// would cost a pass over every edge).
  posegraph::OptimizationReport optimise_keyframes();
  /// The global optimisation of every frame (see above), its Levenberg-Marquardt given at most
  /// max_seconds (OptimizerOptions::max_seconds: cut short, it keeps its last accepted step).
  posegraph::OptimizationReport optimise_all(double max_seconds = std::numeric_limits<double>::infinity());

  /// T_world_keyframe of every node of the keyframe graph, by frame index.
  [[nodiscard]] std::map<std::int64_t, core::SE3> keyframe_poses() const;
  /// Every frame of every local graph added, in frame order, stamped with its colour timestamp.
  [[nodiscard]] core::Trajectory frame_trajectory() const;
  /// The frames of one session's local graphs.
  [[nodiscard]] core::Trajectory frame_trajectory(core::SessionId session) const;
  /// T_piece_odometry: the correction that maps the session's latest tracker poses into its piece
  /// (the map, once placed), from the last frame of its latest local graph; the identity before
  /// any graph of it.
  [[nodiscard]] core::SE3 odometry_correction(core::SessionId session) const;
  /// The first session's correction (one-session callers).
  [[nodiscard]] core::SE3 odometry_correction() const;
  /// The last frame of the session's latest local graph, a keyframe-graph node (none before any
  /// graph of it): where its next graph joins the graph.
  [[nodiscard]] std::optional<posegraph::NodeId> last_node(core::SessionId session) const;

  /// The piece of map a session is in, named by the piece's first session (itself until joined).
  [[nodiscard]] core::SessionId piece(core::SessionId session) const;
  /// In the map: in the first session's piece.
  [[nodiscard]] bool placed(core::SessionId session) const;
  /// The session of a keyframe-graph node.
  [[nodiscard]] core::SessionId session_of(posegraph::NodeId node) const { return session_of_node_.at(node); }
  /// Sessions in the order registered.
  [[nodiscard]] const std::vector<core::SessionId>& sessions() const { return order_; }

  /// Loops in the graph with their χ² and Cauchy weight at the current poses, in insertion order.
  [[nodiscard]] std::vector<LoopState> loops() const;
  /// Loops still waiting for a keyframe.
  [[nodiscard]] std::size_t pending_loops() const { return pending_.size(); }
  /// Loops that entered the graph since the last optimise_keyframes() or optimise_all().
  [[nodiscard]] std::size_t unoptimised_loops() const { return unoptimised_loops_; }

  [[nodiscard]] const posegraph::PoseGraph& keyframe_graph() const { return keyframes_; }

  /// Merges keyframe-graph node `alias` into node `covering` (see the header): T = T_covering^alias,
  /// `information` that of the loop that measured it. Keyframes merged into `alias` before are
  /// re-pointed at `covering` (keyframe_merge.hpp: chained), so an alias always names a node of the
  /// graph. Throws std::invalid_argument when `covering` is not a node of the graph (an alias
  /// included), `alias` is not a node or is fixed (a piece's anchor), or they are one node.
  void merge_keyframe(posegraph::NodeId alias, posegraph::NodeId covering, const core::SE3& T,
                      const core::Matrix6d& information);
  /// A node of the keyframe graph or an alias of one.
  [[nodiscard]] bool holds(posegraph::NodeId node) const {
    return keyframes_.contains(node) || aliases_.contains(node);
  }
  /// The keyframe-graph node a held node is (itself, or the one it was merged into).
  [[nodiscard]] posegraph::NodeId resolve(posegraph::NodeId node) const;
  /// T_piece_node of a held node (an alias: its covering node's pose · T). std::out_of_range if not held.
  [[nodiscard]] core::SE3 pose_of(posegraph::NodeId node) const;
  /// Keyframes merged so far.
  [[nodiscard]] std::size_t merged_keyframes() const { return aliases_.size(); }
  [[nodiscard]] bool merged(posegraph::NodeId node) const { return aliases_.contains(node); }
  /// Local graphs held (settled ones are not).
  [[nodiscard]] std::size_t local_graphs() const { return graphs_.size(); }
  /// Whether the local graph whose keyframe is `keyframe` is held.
  [[nodiscard]] bool has_local_graph(posegraph::NodeId keyframe) const { return graphs_.contains(keyframe); }

  /// Settles merged keyframe `keyframe` (see the header): its local graph's frames are forgotten
  /// and the graph's keyframe edge kept for the global optimisation only (the keyframe graph has
  /// it already); then the keyframe, and the graph's last frame if merged too, are forgotten
  /// altogether when nothing holds them any more (no local graph has them as a frame, no bridge,
  /// no session's anchor or last node): their aliases go, their loops' edges are settled as well.
  /// A merged keyframe is forgotten only once its own graph was settled. nullopt (nothing done)
  /// when `keyframe` is no merged keyframe whose local graph is in and ends at another merged one.
  struct Settled {
    std::vector<posegraph::NodeId> forgotten;
    std::vector<posegraph::Edge> edges;  // the settled edges it changed, as they are now
  };
  std::optional<Settled> settle(posegraph::NodeId keyframe);
  /// A settled edge as settle() left it (a store's record of it, replayed): it becomes the settled
  /// edge between its ends (resolved through aliases), and what it holds beyond the one there
  /// already (information-weighted, keyframe_merge.hpp: increment) enters the keyframe graph.
  /// Throws std::invalid_argument when an end is not held, or the edge is not one an edge may be.
  void apply_settled(const posegraph::Edge& edge);
  /// Registers `alias` as merged into `covering` when the keyframe graph never held it (a store
  /// whose local graphs into and out of it were settled: its own graph follows, or none); a
  /// `covering` merged since is followed to the node it is an alias of. Throws
  /// std::invalid_argument when `alias` is held or `covering` is not.
  void add_alias(posegraph::NodeId alias, posegraph::NodeId covering, const core::SE3& T,
                 const core::Matrix6d& information);
  /// What is wrong with the graph's bookkeeping, nullopt when nothing is: every alias names a node of
  /// the keyframe graph (never an alias: no chains, no cycles) and is no node itself; every node a
  /// session, loop or bridge names is held. Slam::Mapper checks it after every change in a debug
  /// build; tests call it.
  [[nodiscard]] std::optional<std::string> inconsistency() const;
  /// Increases whenever a pose keyframe_poses() or frame_trajectory() returns may have changed.
  [[nodiscard]] std::uint64_t revision() const { return revision_; }
  [[nodiscard]] const BackendParameters& parameters() const { return parameters_; }

 private:
  struct StoredGraph {
    core::SessionId session = 0;
    posegraph::NodeId keyframe = 0;
    LocalSolution solution;
    std::optional<posegraph::Edge> keyframe_edge;  // keyframe -> last frame, as the keyframe graph took it
  };
  struct SessionState {
    std::size_t ordinal = 0;                     // registration order: the earlier piece stays put
    core::SessionId piece = 0;                   // see piece()
    std::optional<posegraph::NodeId> anchor;     // its first keyframe
    std::optional<posegraph::NodeId> last_node;  // last frame of its latest graph
    core::SE3 last_odometry;                     // its tracker pose
  };
  struct StoredLoop {
    loop_closure::LoopClosure loop;
    posegraph::Edge edge;
  };

  [[nodiscard]] posegraph::OptimizerOptions optimizer_options() const;
  [[nodiscard]] std::map<posegraph::NodeId, core::StampedPose> frame_poses(
      std::optional<core::SessionId> session) const;
  void join_keyframe(SessionState& session, posegraph::NodeId keyframe, const LocalFrame& first);
  bool insert_loop(const loop_closure::LoopClosure& loop);
  void join_pieces(const loop_closure::LoopClosure& loop);
  // An edge of the keyframe graph, its ends resolved through aliases, fused into an existing one
  // of its kind between the same nodes, dropped when both ends are one node.
  void add_graph_edge(const posegraph::Edge& edge);
  [[nodiscard]] posegraph::Edge resolved(const posegraph::Edge& edge) const;
  void add_alias_edges(posegraph::PoseGraph& all) const;
  posegraph::Edge add_settled(const posegraph::Edge& edge);  // resolved, fused into settled_: the result
  void repoint_aliases_of(posegraph::NodeId merged);
  bool forget_if_unused(posegraph::NodeId alias, const std::function<void(const posegraph::Edge&)>& settle_edge);
  void follow_aliases(const posegraph::PoseGraph& all);

  BackendParameters parameters_;
  posegraph::PoseGraph keyframes_;
  void sync_incremental();  // keyframes_'s new nodes and factors, moved poses, changed anchors into incremental_

  posegraph::IncrementalOptimizer incremental_;         // the keyframe graph's factor, kept between optimisations
  std::vector<posegraph::Edge> unsynced_;               // factors for incremental_ since the last sync
  std::size_t incremental_factors_ = 0;                 // factors incremental_ holds
  bool rebuild_incremental_ = false;                    // a join moved nodes: build incremental_ anew
  bool rerouting_ = false;                              // merge_keyframe moves k's edges: incremental_ has them on k
  static constexpr std::size_t kIncrementalSlack = 64;  // factors beyond twice the graph's before a rebuild
  static constexpr double kTieStiffness = 1e4;          // a merged keyframe's tie: times the loop's information
  std::map<posegraph::NodeId, StoredGraph> graphs_;     // by keyframe
  std::map<posegraph::NodeId, posegraph::NodeId> graph_ending_at_;  // last frame -> its graph's keyframe
  // Settled contributions (settle()), between keyframe-graph nodes, fused per pair and kind.
  std::map<std::tuple<posegraph::NodeId, posegraph::NodeId, bool>, posegraph::Edge> settled_;
  std::vector<posegraph::Edge> bridges_;
  std::vector<StoredLoop> loops_;
  std::vector<loop_closure::LoopClosure> pending_;
  std::size_t unoptimised_loops_ = 0;
  std::map<core::SessionId, SessionState> sessions_;
  std::vector<core::SessionId> order_;
  std::map<posegraph::NodeId, core::SessionId> session_of_node_;  // keyframe-graph nodes
  std::uint64_t revision_ = 0;
  struct StoredAlias {
    KeyframeAlias alias;
    core::Matrix6d information = core::Matrix6d::Identity();
    bool settled = false;  // its own local graph was settled
  };
  std::map<posegraph::NodeId, StoredAlias> aliases_;  // by alias node
};

}  // namespace cvo::slam
