#include "libcvo/slam/backend.hpp"

#include <stdexcept>
#include <string>
#include <utility>

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

}  // namespace

Backend::Backend(const BackendParameters& parameters)
    : parameters_(parameters), optimizer_(optimizer_options()) {}

posegraph::OptimizerOptions Backend::optimizer_options() const {
  posegraph::OptimizerOptions options;
  options.cauchy_delta = parameters_.cauchy_delta;
  options.max_iterations = parameters_.max_iterations;
  return options;
}

// The graph's keyframe becomes (or already is) a node of the keyframe graph: the first keyframe
// is fixed at its tracker pose; a restart's keyframe is bridged from the previous graph's end.
void Backend::join_keyframe(NodeId keyframe, const LocalFrame& first) {
  if (keyframes_.contains(keyframe)) return;
  if (!last_node_) {
    keyframes_.add_node(keyframe, first.odometry, /*fixed=*/true);
    return;
  }
  const core::SE3 guess = last_odometry_.inverse() * first.odometry;  // the tracker's prediction
  keyframes_.add_node(keyframe, keyframes_.node(*last_node_).pose * guess);
  const posegraph::Edge bridge{*last_node_, keyframe, guess,
                               parameters_.bridge_information * core::Matrix6d::Identity(), false};
  keyframes_.add_edge(bridge);
  bridges_.push_back(bridge);
}

const LocalSolution& Backend::add_local_graph(NodeId keyframe_id, const odometry::LocalGraph& graph) {
  if (graph.empty()) throw std::invalid_argument("backend: empty local graph");
  if (static_cast<NodeId>(graph.keyframe().frame_index) != keyframe_id)
    throw std::invalid_argument("backend: local graph starts at frame " + std::to_string(graph.keyframe().frame_index) +
                                ", not at keyframe " + std::to_string(keyframe_id));
  if (graph_of_keyframe_.contains(keyframe_id))
    throw std::invalid_argument("backend: keyframe " + std::to_string(keyframe_id) + "'s graph was added already");

  LocalSolution solution = optimise_local_graph(graph, optimizer_options());
  join_keyframe(keyframe_id, solution.frames.front());

  // The keyframe→next-keyframe edge (see the header).
  const LocalFrame& last = solution.frames.back();
  if (solution.frames.size() > 1 && !keyframes_.contains(last.id)) {
    keyframes_.add_node(last.id, keyframes_.node(keyframe_id).pose * last.relative);
    keyframes_.add_edge({keyframe_id, last.id, last.relative, information_into(solution, keyframe_id, last.id), false});
  }
  last_node_ = last.id;
  last_odometry_ = last.odometry;

  graph_of_keyframe_.emplace(keyframe_id, graphs_.size());
  graphs_.push_back({keyframe_id, std::move(solution)});
  ++revision_;

  // Loops that waited for a keyframe of this graph.
  std::vector<loop_closure::LoopClosure> waiting;
  waiting.swap(pending_);
  for (const auto& loop : waiting)
    if (!insert_loop(loop)) pending_.push_back(loop);
  return graphs_.back().solution;
}

bool Backend::insert_loop(const loop_closure::LoopClosure& loop) {
  if (!keyframes_.contains(loop.from) || !keyframes_.contains(loop.to)) return false;
  // The detector's information is the residual's already (see the header): no conversion.
  const posegraph::Edge edge{loop.from, loop.to, loop.measurement, 0.5 * (loop.information + loop.information.transpose()),
                             /*robust=*/true};
  keyframes_.add_edge(edge);
  loops_.push_back({loop, edge});
  ++unoptimised_loops_;
  return true;
}

bool Backend::add_loop(const loop_closure::LoopClosure& loop) {
  if (loop.from == loop.to) throw std::invalid_argument("backend: loop from keyframe " + std::to_string(loop.from) + " to itself");
  if (!loop.measurement.is_finite() || !loop.information.allFinite())
    throw std::invalid_argument("backend: loop " + std::to_string(loop.from) + " -> " + std::to_string(loop.to) +
                                " is not finite");
  if (insert_loop(loop)) return true;
  pending_.push_back(loop);
  return false;
}

posegraph::OptimizationReport Backend::optimise_keyframes() {
  unoptimised_loops_ = 0;
  if (keyframes_.nodes().size() < 2) return {};
  auto report = optimizer_.optimize(keyframes_);
  ++revision_;
  return report;
}

posegraph::OptimizationReport Backend::optimise_all() {
  unoptimised_loops_ = 0;
  if (graphs_.empty()) return {};
  const NodeId first = graphs_.front().keyframe;
  posegraph::PoseGraph all;
  for (const auto& [id, stamped] : frame_poses()) all.add_node(id, stamped.pose, id == first);
  for (const auto& g : graphs_)
    for (const auto& e : g.solution.edges) all.add_edge(e);
  for (const auto& e : bridges_) all.add_edge(e);
  for (const auto& l : loops_) all.add_edge(l.edge);
  if (all.nodes().size() < 2) return {};

  auto report = posegraph::optimize(all, optimizer_options());
  for (const auto& [id, node] : keyframes_.nodes()) keyframes_.set_pose(id, all.node(id).pose);
  for (auto& g : graphs_) {
    const core::SE3 keyframe_inverse = all.node(g.keyframe).pose.inverse();
    for (auto& f : g.solution.frames) f.relative = keyframe_inverse * all.node(f.id).pose;
  }
  ++revision_;
  return report;
}

std::map<NodeId, core::StampedPose> Backend::frame_poses() const {
  std::map<NodeId, core::StampedPose> poses;
  for (const auto& g : graphs_) {
    const core::SE3& keyframe = keyframes_.node(g.keyframe).pose;
    for (const auto& f : g.solution.frames)
      poses[f.id] = {f.timestamp, keyframes_.contains(f.id) ? keyframes_.node(f.id).pose : keyframe * f.relative};
  }
  return poses;
}

std::map<std::int64_t, core::SE3> Backend::keyframe_poses() const {
  std::map<std::int64_t, core::SE3> poses;
  for (const auto& [id, node] : keyframes_.nodes()) poses.emplace(id, node.pose);
  return poses;
}

core::Trajectory Backend::frame_trajectory() const {
  core::Trajectory trajectory;
  const auto poses = frame_poses();
  trajectory.reserve(poses.size());
  for (const auto& [id, stamped] : poses) trajectory.push_back(stamped);
  return trajectory;
}

core::SE3 Backend::odometry_correction() const {
  if (!last_node_) return {};
  return keyframes_.node(*last_node_).pose * last_odometry_.inverse();
}

std::vector<LoopState> Backend::loops() const {
  const posegraph::RobustKernel kernel{parameters_.cauchy_delta};
  std::vector<LoopState> states;
  states.reserve(loops_.size());
  for (const auto& l : loops_) {
    const double chi2 = posegraph::edge_chi2(keyframes_, l.edge);
    states.push_back({l.loop, chi2, kernel.weight(chi2, true)});
  }
  return states;
}

}  // namespace cvo::slam
