#include "libcvo/slam/mapper.hpp"

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

bool Mapper::merged(core::SessionId session, std::int64_t keyframe_id) const {
  const auto it = sessions_.find(session);
  if (it == sessions_.end()) return false;
  const auto k = it->second.keyframes.find(keyframe_id);
  return k != it->second.keyframes.end() && k->second.merged;
}

bool Mapper::held(core::SessionId session, std::int64_t keyframe_id) const {
  const auto it = sessions_.find(session);
  if (it == sessions_.end()) return false;
  const auto k = it->second.keyframes.find(keyframe_id);
  if (k == it->second.keyframes.end()) return false;
  const posegraph::NodeId n = node(it->second, k->second.frame);
  return backend_.holds(n) && backend_.keyframe_graph().contains(backend_.resolve(n));
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
    if (k.id <= it->second.settled_through)
      throw MapperError(name(k.session, k.id) + " is older than its session's settled keyframes (settle())");
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
  if (s.robot.empty()) s.robot = k.robot;
  const posegraph::NodeId id = node(s, frame);
  loop_closure::KeyframePlacement placement{id, std::nullopt, {}, backend_.piece(k.session), std::nullopt};
  if (const auto after = s.keyframes.upper_bound(k.id); after != s.keyframes.begin())
    placement.previous = node(s, std::prev(after)->second.frame);    // η's normaliser: its predecessor
  if (placement.previous && backend_.merged(*placement.previous)) {  // or the keyframe covering it
    placement.previous = backend_.resolve(*placement.previous);
    placement.previous_is_candidate = true;
  }
  placement.pose = backend_.holds(id) ? backend_.pose_of(id) : backend_.odometry_correction(k.session) * k.odometry;

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
  const FoundLoops found{std::move(loops), detector_.last_confirmations()};
  const auto first = first_loops(s, k.id, id);  // before this keyframe may be merged
  if (auto merged = enter_loops(s, merge_of(k.session, k.id, s.keyframes.at(k.id)), id, found, outcome))
    outcome.merges.push_back(std::move(*merged));
  if (!placement.previous) s.undetected_first = k.id;
  if (first)
    if (auto m = merge_first(s, *first)) outcome.merges.push_back(std::move(*m));
  outcome.joined = after_change();
  return outcome;
}

void Mapper::enter_loop(Session& s, const loop_closure::LoopClosure& loop, double time, KeyframeOutcome& outcome) {
  backend_.add_loop(loop);
  const std::size_t key = loops_accepted_++;
  loops_.emplace(key, loop);
  outcome.loops.push_back(describe(loop));
  if (const MapLoop& m = outcome.loops.back(); m.from_session != m.to_session)
    for (const core::SessionId end : {m.from_session, m.to_session}) sessions_.at(end).loops.push_back(key);
  s.last_match_time = time;
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
  if (const auto it = sessions_.find(session_id);
      it != sessions_.end() && keyframe_id <= it->second.settled_through && !knows(session_id, keyframe_id))
    throw MapperError("local graph of " + name(session_id, keyframe_id) + ": the keyframe was settled and forgotten");
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
    ++optimisations_;
    marginals_.invalidate();
    std::map<std::int64_t, loop_closure::PlacedPose> poses;
    for (const auto& [id, pose] : backend_.keyframe_poses())
      poses.emplace(id, loop_closure::PlacedPose{pose, backend_.piece(backend_.session_of(id))});
    detector_.update_poses(poses);
  } else {
    marginals_.follow(backend_.keyframe_graph());  // new leaves carry the covariances along
  }
  marginals_.keep(covariance_nodes());
  check_in_debug();
  std::vector<core::SessionId> joined;
  for (const core::SessionId id : order_) {
    Session& s = sessions_.at(id);
    if (s.joined_at_keyframe >= 0 || !backend_.placed(id)) continue;
    s.joined_at_keyframe = s.keyframes.empty() ? 0 : s.keyframes.rbegin()->first;
    joined.push_back(id);
  }
  return joined;
}

posegraph::OptimizationReport Mapper::finish(double max_seconds) {
  auto report = backend_.optimise_all(max_seconds);
  ++revision_;
  ++optimisations_;
  marginals_.invalidate();
  check_in_debug();
  return report;
}

std::optional<std::string> Mapper::inconsistency() const {
  if (auto why = backend_.inconsistency()) return why;
  for (const auto& [id, s] : sessions_)
    for (const auto& [keyframe, record] : s.keyframes)
      if (record.merged && !backend_.merged(node(s, record.frame)))
        return name(id, keyframe) + " is recorded as merged but is no alias of the keyframe graph";
  return std::nullopt;
}

// A broken invariant is the mapper's own fault: thrown where it arose, not where it is later tripped over.
void Mapper::check_in_debug() const {
#ifndef NDEBUG
  if (const auto why = inconsistency()) throw std::logic_error("mapper: " + *why);
#endif
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

std::optional<std::pair<std::int64_t, posegraph::NodeId>> Mapper::newest_in_graph(const Session& s) const {
  const auto& graph = backend_.keyframe_graph();
  for (auto k = s.keyframes.rbegin(); k != s.keyframes.rend(); ++k)
    if (const auto n = node(s, k->second.frame); graph.contains(n)) return std::pair{k->first, n};
  return std::nullopt;
}

// What keyframe covariances need: each session's newest keyframe in the graph, and the last node of
// its latest local graph, which its next graph's leaf hangs from.
std::vector<posegraph::NodeId> Mapper::covariance_nodes() const {
  std::vector<posegraph::NodeId> nodes;
  for (const auto& [id, s] : sessions_) {
    if (const auto newest = newest_in_graph(s)) nodes.push_back(newest->second);
    if (auto last = backend_.last_node(id)) {
      last = backend_.resolve(*last);
      if (nodes.empty() || nodes.back() != *last) nodes.push_back(*last);
    }
  }
  return nodes;
}

// The marginal covariance of a keyframe-graph node, the map's uncertainty of where it is
// (keyframe_marginals.hpp): held, or one factorisation for every session's.
std::optional<core::Matrix6d> Mapper::keyframe_covariance(posegraph::NodeId n) const {
  if (auto held = marginals_.find(n)) return held;
  if (!marginals_.worth_computing()) return std::nullopt;
  posegraph::OptimizerOptions options;
  options.pose_graph = backend_.parameters();
  marginals_.compute(backend_.keyframe_graph(), covariance_nodes(), options);
  return marginals_.find(n);
}

MapSession Mapper::describe(core::SessionId id, const Session& s) const {
  MapSession entry;
  entry.session = id;
  entry.placed = backend_.placed(id);
  entry.piece = backend_.piece(id);
  entry.keyframes = s.keyframes.size() + s.forgotten_before + s.forgotten;
  entry.joined_at_keyframe = s.joined_at_keyframe;
  entry.robot = s.robot;
  entry.correction = backend_.odometry_correction(id);
  entry.state = s.lost         ? core::LocalizationState::kLost
                : entry.placed ? core::LocalizationState::kLocalized
                               : core::LocalizationState::kLocalizing;
  // The first session is the map: each of its keyframes is in it.
  entry.last_match_time =
      id == order_.front() && !s.keyframes.empty() ? s.keyframes.rbegin()->second.timestamp : s.last_match_time;
  if (const auto newest = newest_in_graph(s))
    if (auto covariance = keyframe_covariance(newest->second)) {
      entry.covariance_keyframe = newest->first;
      entry.keyframe_covariance = *covariance;
    }
  if (entry.last_match_time >= 0 && !s.keyframes.empty())
    entry.since_match_s = s.keyframes.rbegin()->second.timestamp - entry.last_match_time;
  return entry;
}

Map Mapper::map() const {
  Map map;
  map.revision = revision();
  const auto poses = backend_.keyframe_poses();
  for (const core::SessionId id : order_) {
    const Session& s = sessions_.at(id);
    map.sessions.push_back(describe(id, s));
    const core::SE3& correction = map.sessions.back().correction;
    for (const auto& [keyframe, record] : s.keyframes) {
      if (record.merged) continue;  // the map follows the area (see the header)
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

std::vector<core::SessionId> Mapper::sessions() const {
  std::vector<core::SessionId> out = order_;
  for (const auto& [id, v] : visitors_) out.push_back(id);
  return out;
}

SessionCorrection Mapper::correction(core::SessionId id, std::size_t max_loops) const {
  SessionCorrection c{revision(), session(id), {}};
  const auto it = sessions_.find(id);
  if (it == sessions_.end()) return c;
  for (auto i = it->second.loops.rbegin(); i != it->second.loops.rend() && c.loops.size() < max_loops; ++i) {
    const loop_closure::LoopClosure& loop = loops_.at(*i);
    if (!backend_.holds(loop.from) || !backend_.holds(loop.to)) continue;  // waiting: not in the map yet
    const MapLoop m = describe(loop);
    const bool from_own = m.from_session == id;
    c.loops.push_back({from_own ? m.from_id : m.to_id, from_own ? m.to_session : m.from_session,
                       from_own ? m.to_id : m.from_id, from_own ? loop.measurement : loop.measurement.inverse(),
                       backend_.pose_of(from_own ? loop.to : loop.from)});
  }
  return c;
}

core::Trajectory Mapper::frame_trajectory(core::SessionId session) const { return backend_.frame_trajectory(session); }

}  // namespace cvo::slam
