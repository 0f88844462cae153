#include "libcvo/slam/backend.hpp"

#include <chrono>
#include <stdexcept>
#include <string>
#include <utility>

#include "libcvo/core/information.hpp"
#include "libcvo/posegraph/cost.hpp"

namespace cvo::slam {
namespace {

using posegraph::NodeId;

// The information of the keyframe→`to` edge, or (should the tracker ever leave it out) of the
// last edge into `to`: every non-keyframe node of a local graph has an edge into it.
core::Matrix6d information_into(const LocalSolution& s, NodeId keyframe, NodeId to) {
  const posegraph::Edge* into = nullptr;
  for (const auto& e : s.edges) {
    if (e.to != to) continue;
    if (e.from == keyframe) return e.information;
    into = &e;
  }
  if (into == nullptr) throw std::invalid_argument("local graph: no edge into frame " + std::to_string(to));
  return into->information;
}

// Incoming information must pass core::check_information (finite, symmetric, positive
// semi-definite): one that does not would make the graph's cost unbounded below.
void require_information(const std::string& edge, const core::Matrix6d& information) {
  if (const auto check = core::check_information(information); !check.ok())
    throw std::invalid_argument("backend: " + edge + ": " + check.why());
}

posegraph::IncrementalOptions incremental_options(const BackendParameters& parameters) {
  posegraph::IncrementalOptions options;
  options.pose_graph = parameters;
  return options;
}

}  // namespace

Backend::Backend(const BackendParameters& parameters)
    : parameters_(parameters), incremental_(incremental_options(parameters)) {}

posegraph::OptimizerOptions Backend::optimizer_options() const {
  posegraph::OptimizerOptions options;
  options.pose_graph = parameters_;
  return options;
}

void Backend::add_session(core::SessionId session) {
  if (sessions_.contains(session)) return;
  sessions_.emplace(session, SessionState{order_.size(), session, std::nullopt, std::nullopt, {}});
  order_.push_back(session);
}

core::SessionId Backend::piece(core::SessionId session) const {
  const auto it = sessions_.find(session);
  return it == sessions_.end() ? session : it->second.piece;
}

bool Backend::placed(core::SessionId session) const { return !order_.empty() && piece(session) == order_.front(); }

// The graph's keyframe becomes (or already is) a node of the keyframe graph: a session's first
// keyframe anchors its piece at its tracker pose; a restart's keyframe is bridged from the end of
// the session's previous graph.
void Backend::join_keyframe(SessionState& session, NodeId keyframe, const LocalFrame& first) {
  if (holds(keyframe)) return;
  if (!session.last_node) {
    keyframes_.add_node(keyframe, first.odometry, /*fixed=*/true);
    session.anchor = keyframe;
    return;
  }
  const core::SE3 guess = session.last_odometry.inverse() * first.odometry;  // the tracker's prediction
  keyframes_.add_node(keyframe, pose_of(*session.last_node) * guess);
  const posegraph::Edge bridge{*session.last_node, keyframe, guess,
                               parameters_.bridge_information * core::Matrix6d::Identity(), false};
  add_graph_edge(bridge);
  bridges_.push_back(bridge);
}

const LocalSolution& Backend::add_local_graph(NodeId keyframe_id, const odometry::LocalGraph& graph) {
  return add_local_graph(order_.empty() ? core::SessionId{0} : order_.front(), keyframe_id, graph);
}

const LocalSolution& Backend::add_local_graph(core::SessionId session_id, NodeId keyframe_id,
                                              const odometry::LocalGraph& graph) {
  if (graph.empty()) throw std::invalid_argument("backend: empty local graph");
  if (static_cast<NodeId>(graph.keyframe().frame_index) != keyframe_id)
    throw std::invalid_argument("backend: local graph starts at frame " + std::to_string(graph.keyframe().frame_index) +
                                ", not at keyframe " + std::to_string(keyframe_id));
  if (graphs_.contains(keyframe_id))
    throw std::invalid_argument("backend: keyframe " + std::to_string(keyframe_id) + "'s graph was added already");
  for (const auto& n : graph.nodes())
    if (const auto it = session_of_node_.find(static_cast<NodeId>(n.frame_index));
        it != session_of_node_.end() && it->second != session_id)
      throw std::invalid_argument("backend: frame " + std::to_string(n.frame_index) + " belongs to another session");
  for (const auto& e : graph.edges())
    require_information("local graph edge " + std::to_string(e.from) + " -> " + std::to_string(e.to), e.information);

  LocalSolution solution = optimise_local_graph(graph, optimizer_options());
  add_session(session_id);
  SessionState& session = sessions_.at(session_id);
  join_keyframe(session, keyframe_id, solution.frames.front());
  session_of_node_.emplace(keyframe_id, session_id);

  // The keyframe→next-keyframe edge (see the header).
  const LocalFrame& last = solution.frames.back();
  std::optional<posegraph::Edge> keyframe_edge;
  if (solution.frames.size() > 1)
    keyframe_edge = {keyframe_id, last.id, last.relative, information_into(solution, keyframe_id, last.id), false};
  if (keyframe_edge && !holds(last.id)) {
    keyframes_.add_node(last.id, pose_of(keyframe_id) * last.relative);
    add_graph_edge(*keyframe_edge);
    session_of_node_.emplace(last.id, session_id);
  } else if (keyframe_edge && aliases_.contains(last.id) && !graph_ending_at_.contains(last.id)) {
    add_graph_edge(*keyframe_edge);  // into a keyframe a store registered merged before its graph came
  }
  session.last_node = last.id;
  session.last_odometry = last.odometry;

  if (keyframe_edge) graph_ending_at_[last.id] = keyframe_id;
  const auto stored =
      graphs_.insert_or_assign(keyframe_id, StoredGraph{session_id, keyframe_id, std::move(solution), keyframe_edge});
  ++revision_;

  // Loops that waited for a keyframe of this graph.
  std::vector<loop_closure::LoopClosure> waiting;
  waiting.swap(pending_);
  for (const auto& loop : waiting)
    if (!insert_loop(loop)) pending_.push_back(loop);
  return stored.first->second.solution;
}

bool Backend::insert_loop(const loop_closure::LoopClosure& loop) {
  if (!holds(loop.from) || !holds(loop.to)) return false;
  if (piece(session_of(loop.from)) != piece(session_of(loop.to))) join_pieces(loop);
  // The detector's information is the residual's already (see the header): no conversion.
  const posegraph::Edge edge{loop.from, loop.to, loop.measurement,
                             0.5 * (loop.information + loop.information.transpose()),
                             /*robust=*/true};
  add_graph_edge(edge);
  loops_.push_back({loop, edge});
  ++unoptimised_loops_;
  return true;
}

// The later piece moves rigidly onto the loop: T_piece(to) = T_piece(from) · Z (Z = T_from^to).
void Backend::join_pieces(const loop_closure::LoopClosure& loop) {
  const core::SessionId a = piece(session_of(loop.from)), b = piece(session_of(loop.to));
  const bool move_to_side = sessions_.at(b).ordinal > sessions_.at(a).ordinal;
  const core::SessionId keep = move_to_side ? a : b, moved = move_to_side ? b : a;
  const core::SE3 from = pose_of(loop.from);
  const core::SE3 to = pose_of(loop.to);
  const core::SE3 move =
      move_to_side ? from * loop.measurement * to.inverse() : to * loop.measurement.inverse() * from.inverse();
  for (const auto& [id, node] : std::map<NodeId, posegraph::Node>(keyframes_.nodes()))
    if (piece(session_of(id)) == moved) keyframes_.set_pose(id, move * node.pose);
  rebuild_incremental_ = true;  // its merged keyframes' nodes there stayed behind
  for (auto& [id, s] : sessions_)
    if (s.piece == moved) s.piece = keep;
  if (const auto& anchor = sessions_.at(moved).anchor) keyframes_.set_fixed(*anchor, false);
}

bool Backend::add_loop(const loop_closure::LoopClosure& loop) {
  if (loop.from == loop.to)
    throw std::invalid_argument("backend: loop from keyframe " + std::to_string(loop.from) + " to itself");
  const std::string name = "loop " + std::to_string(loop.from) + " -> " + std::to_string(loop.to);
  if (!loop.measurement.is_finite()) throw std::invalid_argument("backend: " + name + " is not finite");
  require_information(name, loop.information);
  if (insert_loop(loop)) return true;
  pending_.push_back(loop);
  return false;
}

namespace {
bool same_pose(const core::SE3& a, const core::SE3& b) {
  return a.translation() == b.translation() && a.rotation().coeffs() == b.rotation().coeffs();
}
}  // namespace

// incremental_ holds the keyframe graph as factors (see the header): each factor that entered
// keyframes_ (a new edge, or the contribution fused into an existing one: to first order the two
// quadratics add up to the fused one) and, for a merged keyframe, its old factors on its own node
// with a tie to the covering keyframe. It is built anew from keyframes_ when a join moved nodes
// apart (aliases included) or it holds twice the factors keyframes_ has (merges and fusions add
// factors the keyframe graph does not keep), so that it stays as small as the keyframe graph,
// once per as many changes as the graph has edges.
void Backend::sync_incremental() {
  const std::size_t bound = 2 * keyframes_.edges().size() + kIncrementalSlack;
  if (rebuild_incremental_ || incremental_factors_ + unsynced_.size() > bound) {
    incremental_ = posegraph::IncrementalOptimizer(incremental_options(parameters_));
    incremental_factors_ = 0;
    unsynced_ = keyframes_.edges();
    rebuild_incremental_ = false;
  }
  for (const auto& [id, node] : keyframes_.nodes()) {
    if (!incremental_.contains(id)) {
      incremental_.add_node(id, node.pose, node.fixed);
      continue;
    }
    if (incremental_.fixed(id) != node.fixed) incremental_.set_fixed(id, node.fixed);
    if (!same_pose(incremental_.pose(id), node.pose)) incremental_.set_pose(id, node.pose);
  }
  for (const auto& e : unsynced_) incremental_.add_edge(e);
  incremental_factors_ += unsynced_.size();
  unsynced_.clear();
}

posegraph::OptimizationReport Backend::optimise_keyframes() {
  unoptimised_loops_ = 0;
  if (keyframes_.nodes().size() < 2) return {};
  const auto start = std::chrono::steady_clock::now();
  sync_incremental();
  posegraph::OptimizationReport report;
  const double threshold = posegraph::IncrementalOptions{}.relinearise_threshold;
  report.stop_reason = "maximum iterations";
  for (int k = 0; k < parameters_.max_iterations; ++k) {
    const posegraph::UpdateReport update = incremental_.update(threshold);
    ++report.iterations;
    report.factorizations += update.rebuilt ? 1 : 0;
    if (k > 0 && update.relinearised_nodes == 0) {
      report.converged = true;
      report.stop_reason = "no node moved beyond the relinearisation threshold";
      break;
    }
  }
  for (const auto& [id, node] : std::map<NodeId, posegraph::Node>(keyframes_.nodes()))
    if (!node.fixed) keyframes_.set_pose(id, incremental_.pose(id));
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ++revision_;
  return report;
}

posegraph::OptimizationReport Backend::optimise_all(double max_seconds) {
  unoptimised_loops_ = 0;
  if (graphs_.empty()) return {};
  posegraph::PoseGraph all;  // each piece held at its anchor, as in the keyframe graph
  for (const auto& [id, stamped] : frame_poses(std::nullopt))
    all.add_node(id, stamped.pose, keyframes_.contains(id) && keyframes_.node(id).fixed);
  for (const auto& [id, node] : keyframes_.nodes())  // a node whose frames were settled
    if (!all.contains(id)) all.add_node(id, node.pose, node.fixed);
  for (const auto& [keyframe, g] : graphs_)
    for (const auto& e : g.solution.edges) all.add_edge(e);
  const auto add = [&](const posegraph::Edge& e) {  // an end without frames: through its alias
    const posegraph::Edge r = all.contains(e.from) && all.contains(e.to) ? e : resolved(e);
    if (r.from != r.to) all.add_edge(r);
  };
  for (const auto& e : bridges_) add(e);
  for (const auto& l : loops_) add(l.edge);
  for (const auto& [ends, e] : settled_) all.add_edge(e);
  add_alias_edges(all);
  if (all.nodes().size() < 2) return {};

  auto options = optimizer_options();
  options.max_seconds = max_seconds;
  auto report = posegraph::optimize(all, options);
  for (const auto& [id, node] : keyframes_.nodes()) keyframes_.set_pose(id, all.node(id).pose);
  follow_aliases(all);
  for (auto& [keyframe, g] : graphs_) {
    const core::SE3 keyframe_inverse = all.node(g.keyframe).pose.inverse();
    for (auto& f : g.solution.frames) f.relative = keyframe_inverse * all.node(f.id).pose;
  }
  ++revision_;
  return report;
}

std::map<NodeId, core::StampedPose> Backend::frame_poses(std::optional<core::SessionId> session) const {
  std::map<NodeId, core::StampedPose> poses;
  for (const auto& [keyframe_id, g] : graphs_) {
    if (session && g.session != *session) continue;
    const core::SE3 keyframe = pose_of(g.keyframe);
    for (const auto& f : g.solution.frames)
      poses[f.id] = {f.timestamp, holds(f.id) ? pose_of(f.id) : keyframe * f.relative};
  }
  return poses;
}

std::map<std::int64_t, core::SE3> Backend::keyframe_poses() const {
  std::map<std::int64_t, core::SE3> poses;
  for (const auto& [id, node] : keyframes_.nodes()) poses.emplace(id, node.pose);
  return poses;
}

namespace {
core::Trajectory to_trajectory(const std::map<NodeId, core::StampedPose>& poses) {
  core::Trajectory trajectory;
  trajectory.reserve(poses.size());
  for (const auto& [id, stamped] : poses) trajectory.push_back(stamped);
  return trajectory;
}
}  // namespace

core::Trajectory Backend::frame_trajectory() const { return to_trajectory(frame_poses(std::nullopt)); }
core::Trajectory Backend::frame_trajectory(core::SessionId session) const {
  return to_trajectory(frame_poses(session));
}

core::SE3 Backend::odometry_correction(core::SessionId session) const {
  const auto it = sessions_.find(session);
  if (it == sessions_.end() || !it->second.last_node) return {};
  return pose_of(*it->second.last_node) * it->second.last_odometry.inverse();
}

std::optional<NodeId> Backend::last_node(core::SessionId session) const {
  const auto it = sessions_.find(session);
  return it == sessions_.end() ? std::nullopt : it->second.last_node;
}

core::SE3 Backend::odometry_correction() const {
  return order_.empty() ? core::SE3() : odometry_correction(order_.front());
}

std::vector<LoopState> Backend::loops() const {
  const posegraph::RobustKernel kernel{parameters_.cauchy_delta};
  std::vector<LoopState> states;
  states.reserve(loops_.size());
  for (const auto& l : loops_) {
    const posegraph::Edge edge = resolved(l.edge);
    const double chi2 = edge.from == edge.to ? 0.0 : posegraph::edge_chi2(keyframes_, edge);
    states.push_back({l.loop, chi2, kernel.weight(chi2, true)});
  }
  return states;
}

}  // namespace cvo::slam
