#include "libcvo/slam/mapper.hpp"

#include "libcvo/posegraph/marginals.hpp"

#include <algorithm>
#include <tuple>
#include <utility>

namespace cvo::slam {
namespace {

constexpr int kFrameBits = 40;
constexpr std::int64_t kMaxFrame = std::int64_t{1} << kFrameBits;

std::string name(core::SessionId session, std::int64_t id) {
  return "keyframe " + std::to_string(id) + " of session " + core::session_name(session);
}

// The graph with its frame indices moved by `offset` (node ids of the Backend).
odometry::LocalGraph renumbered(const odometry::LocalGraph& graph, std::int64_t offset) {
  odometry::LocalGraph out(graph.nodes().size());
  const auto shift = [&](std::uint64_t frame) { return frame + static_cast<std::uint64_t>(offset); };
  for (auto n : graph.nodes()) {
    n.frame_index = shift(n.frame_index);
    out.add_node(n);
  }
  for (auto e : graph.edges()) {
    e.from = shift(e.from);
    e.to = shift(e.to);
    out.add_edge(e);
  }
  return out;
}

bool same_pose(const core::SE3& a, const core::SE3& b) {
  return (a.translation() - b.translation()).norm() < 1e-9 && a.rotation().isApprox(b.rotation(), 1e-9);
}

}  // namespace

Mapper::Mapper(loop_closure::Vocabulary vocabulary, const MapperParameters& parameters)
    : detector_(std::move(vocabulary), parameters.detector),
      backend_(parameters.backend),
      localization_(parameters.localization) {}

Mapper::Session& Mapper::enter(core::SessionId id) {
  if (const auto it = sessions_.find(id); it != sessions_.end()) return it->second;
  order_.push_back(id);
  backend_.add_session(id);
  auto& s = sessions_[id];
  s.ordinal = next_ordinal_++;
  if (order_.size() == 1) s.joined_at_keyframe = 0;  // the first session defines the map
  return s;
}

posegraph::NodeId Mapper::node(const Session& s, std::int64_t frame) const { return (s.ordinal << kFrameBits) | frame; }

bool Mapper::knows(core::SessionId session, std::int64_t keyframe_id) const {
  if (const auto v = visitors_.find(session); v != visitors_.end())
    return std::any_of(v->second.window.begin(), v->second.window.end(),
                       [&](const WindowKeyframe& w) { return w.id == keyframe_id; });
  const auto it = sessions_.find(session);
  return it != sessions_.end() && it->second.keyframes.contains(keyframe_id);
}

KeyframeOutcome Mapper::add_keyframe(const SessionKeyframe& k) {
  const auto frame = static_cast<std::int64_t>(k.frame.index);
  if (frame >= kMaxFrame)
    throw MapperError(name(k.session, k.id) + ": frame index " + std::to_string(frame) + " is 2^40 or more");
  if (k.id < 0) throw MapperError(name(k.session, k.id) + ": negative id");
  if (map_below_ && !sessions_.contains(k.session)) return visit(k);
  if (const auto it = sessions_.find(k.session); it != sessions_.end()) {
    const auto& keyframes = it->second.keyframes;
    if (const auto same = keyframes.find(k.id); same != keyframes.end()) {
      if (same->second.frame == frame && same->second.timestamp == k.frame.timestamp &&
          same_pose(same->second.odometry, k.odometry)) {
        KeyframeOutcome duplicate;
        duplicate.duplicate = true;
        return duplicate;
      }
      throw MapperError(name(k.session, k.id) + " is known with other content (frame " +
                        std::to_string(same->second.frame) + ", not " + std::to_string(frame) + ")");
    }
    // Keyframes may come late (a re-sent one), but ids and frames must keep one order.
    const auto after = keyframes.upper_bound(k.id);
    const bool below_ok = after == keyframes.begin() || std::prev(after)->second.frame < frame;
    const bool above_ok = after == keyframes.end() || after->second.frame > frame;
    if (!below_ok || !above_ok)
      throw MapperError(name(k.session, k.id) + " (frame " + std::to_string(frame) +
                        ") is out of order with the session's other keyframes");
    if (map_below_) throw MapperError(name(k.session, k.id) + " is new to a stored session: the map is read only");
  }

  Session& s = enter(k.session);
  const posegraph::NodeId id = node(s, frame);
  loop_closure::KeyframePlacement placement{id, std::nullopt, {}, backend_.piece(k.session), std::nullopt};
  if (const auto after = s.keyframes.upper_bound(k.id); after != s.keyframes.begin())
    placement.previous = node(s, std::prev(after)->second.frame);  // η's normaliser: its predecessor
  const auto& graph = backend_.keyframe_graph();
  placement.pose = graph.contains(id) ? graph.node(id).pose : backend_.odometry_correction(k.session) * k.odometry;

  std::vector<loop_closure::LoopClosure> loops;
  try {
    loops = detector_.add_keyframe(placement, k.frame, k.cloud);
  } catch (const std::exception& e) {
    throw MapperError(name(k.session, k.id) + ": " + e.what());
  }
  s.keyframes.emplace(k.id, KeyframeRecord{frame, k.frame.timestamp, k.odometry});
  keyframe_of_node_.emplace(id, std::pair{k.session, k.id});
  ++revision_;

  KeyframeOutcome outcome;
  outcome.loops_tried = detector_.last_attempts().size();
  loops_tried_ += outcome.loops_tried;
  for (const auto& loop : loops) {
    backend_.add_loop(loop);
    loops_.push_back(loop);
    outcome.loops.push_back(describe(loop));
    s.last_match_time = k.frame.timestamp;
  }
  outcome.joined = after_change();
  return outcome;
}

std::vector<core::SessionId> Mapper::add_local_graph(core::SessionId session_id, std::int64_t keyframe_id,
                                                     const odometry::LocalGraph& graph) {
  if (graph.empty()) throw MapperError("local graph of " + name(session_id, keyframe_id) + " is empty");
  const auto first = static_cast<std::int64_t>(graph.keyframe().frame_index);
  for (const auto& n : graph.nodes())
    if (n.frame_index >= static_cast<std::uint64_t>(kMaxFrame))
      throw MapperError("local graph of " + name(session_id, keyframe_id) + ": frame index 2^40 or more");
  if (const auto it = sessions_.find(session_id); it != sessions_.end())
    if (const auto k = it->second.keyframes.find(keyframe_id);
        k != it->second.keyframes.end() && k->second.frame != first)
      throw MapperError("local graph of " + name(session_id, keyframe_id) + " starts at frame " +
                        std::to_string(first) + ", the keyframe is frame " + std::to_string(k->second.frame));
  if (map_below_ && !sessions_.contains(session_id)) {
    if (auto v = visitors_.find(session_id); v != visitors_.end()) add_window_graph(v->second, keyframe_id, graph);
    return {};
  }
  if (map_below_ && !knows(session_id, keyframe_id))
    throw MapperError("local graph of " + name(session_id, keyframe_id) + " is new to the map, which is read only");
  // The Backend checks the rest before it changes anything; a session a refused graph introduced
  // stays registered without nodes (harmless: it is placed by nothing).
  const Session& s = enter(session_id);
  const auto offset = node(s, 0);
  try {
    backend_.add_local_graph(session_id, offset + first, renumbered(graph, offset));
  } catch (const std::exception& e) {
    throw MapperError("local graph of " + name(session_id, keyframe_id) + ": " + e.what());
  }
  ++revision_;
  return after_change();
}

std::vector<core::SessionId> Mapper::after_change() {
  if (backend_.unoptimised_loops() > 0) {  // new loops, or waiting ones that just found their keyframe
    backend_.optimise_keyframes();
    std::map<std::int64_t, loop_closure::PlacedPose> poses;
    for (const auto& [id, pose] : backend_.keyframe_poses())
      poses.emplace(id, loop_closure::PlacedPose{pose, backend_.piece(backend_.session_of(id))});
    detector_.update_poses(poses);
  }
  std::vector<core::SessionId> joined;
  for (const core::SessionId id : order_) {
    Session& s = sessions_.at(id);
    if (s.joined_at_keyframe >= 0 || !backend_.placed(id)) continue;
    s.joined_at_keyframe = s.keyframes.empty() ? 0 : s.keyframes.rbegin()->first;
    joined.push_back(id);
  }
  return joined;
}

posegraph::OptimizationReport Mapper::finish() {
  auto report = backend_.optimise_all();
  ++revision_;
  return report;
}

MapLoop Mapper::describe(const loop_closure::LoopClosure& loop) const {
  MapLoop m;
  m.loop = loop;
  std::tie(m.from_session, m.from_id) = keyframe_of_node_.at(loop.from);
  std::tie(m.to_session, m.to_id) = keyframe_of_node_.at(loop.to);
  m.from_frame = loop.from & (kMaxFrame - 1);
  m.to_frame = loop.to & (kMaxFrame - 1);
  return m;
}

// The marginal covariance of each session's newest keyframe in the keyframe graph (the map's
// uncertainty of where it is, posegraph/marginals.hpp), keyed by session: one factorisation for all.
std::map<core::SessionId, std::pair<std::int64_t, core::Matrix6d>> Mapper::keyframe_covariances() const {
  std::map<core::SessionId, std::pair<std::int64_t, core::Matrix6d>> out;
  const auto& graph = backend_.keyframe_graph();
  std::map<posegraph::NodeId, std::pair<core::SessionId, std::int64_t>> newest;
  for (const auto& [id, s] : sessions_)
    for (auto k = s.keyframes.rbegin(); k != s.keyframes.rend(); ++k)
      if (const auto n = node(s, k->second.frame); graph.contains(n)) {
        newest.emplace(n, std::pair{id, k->first});
        break;
      }
  if (newest.empty()) return out;
  std::vector<posegraph::NodeId> nodes;
  for (const auto& [n, key] : newest) nodes.push_back(n);
  posegraph::OptimizerOptions options;
  options.pose_graph = backend_.parameters();
  try {
    for (const auto& [n, covariance] : posegraph::marginal_covariances(graph, nodes, options))
      out.emplace(newest.at(n).first, std::pair{newest.at(n).second, covariance});
  } catch (const std::runtime_error&) {  // a piece no edge holds yet: no covariances this time
  }
  return out;
}

Map Mapper::map() const {
  Map map;
  map.revision = revision_ + backend_.revision();
  const auto poses = backend_.keyframe_poses();
  const auto covariances = keyframe_covariances();
  for (const core::SessionId id : order_) {
    const Session& s = sessions_.at(id);
    const core::SE3 correction = backend_.odometry_correction(id);
    MapSession& entry = map.sessions.emplace_back();
    entry.session = id;
    entry.placed = backend_.placed(id);
    entry.piece = backend_.piece(id);
    entry.keyframes = s.keyframes.size();
    entry.joined_at_keyframe = s.joined_at_keyframe;
    entry.correction = correction;
    entry.state = s.lost                ? core::LocalizationState::kLost
                  : backend_.placed(id) ? core::LocalizationState::kLocalized
                                        : core::LocalizationState::kLocalizing;
    // The first session is the map: each of its keyframes is in it.
    entry.last_match_time =
        id == order_.front() && !s.keyframes.empty() ? s.keyframes.rbegin()->second.timestamp : s.last_match_time;
    if (const auto c = covariances.find(id); c != covariances.end()) {
      entry.covariance_keyframe = c->second.first;
      entry.keyframe_covariance = c->second.second;
    }
    if (entry.last_match_time >= 0 && !s.keyframes.empty())
      entry.since_match_s = s.keyframes.rbegin()->second.timestamp - entry.last_match_time;
    for (const auto& [keyframe, record] : s.keyframes) {
      // A keyframe whose local graph has not closed yet follows its session's newest correction.
      const auto it = poses.find(node(s, record.frame));
      map.keyframes.push_back(
          {id, keyframe, record.timestamp, it != poses.end() ? it->second : correction * record.odometry});
    }
  }
  for (const auto& [id, v] : visitors_) map.sessions.push_back(describe(id, v));
  const auto states = backend_.loops();
  for (const auto& state : states) {
    MapLoop m = describe(state.loop);
    m.chi2 = state.chi2;
    m.weight = state.weight;
    map.loops.push_back(m);
  }
  return map;
}

core::Trajectory Mapper::frame_trajectory(core::SessionId session) const { return backend_.frame_trajectory(session); }

}  // namespace cvo::slam
