#pragma once
// The SLAM back end as one object, for every caller (cvo-run --mode slam, cvo-backendd, cvo-map):
// keyframes and closed local graphs of any number of tracker sessions in, a multi-session map out
// (what CVO_MAP carries: map(); one session's entry, what CVO_MAP_CORRECTION carries: correction()).
// The first session seen defines the map frame; a later one joins it at its first verified loop to
// the map. After localize_only() the map is read only and new sessions are localized in it. A
// revisit's keyframes that an earlier keyframe covers are merged into it, and settled once old.
// How and why each works (covariances, sessions, node ids, localization, revisits): README.md.
//
// Everything that cannot be applied throws MapperError before anything changed, with a message
// naming the session and keyframe; the mapper stays usable.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/loop_closure/loop_detector.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/odometry/local_graph.hpp"
#include "libcvo/registration/point_cloud.hpp"
#include "libcvo/slam/backend.hpp"
#include "libcvo/slam/keyframe_marginals.hpp"
#include "libcvo/slam/localization_window.hpp"

namespace cvo::slam {

class MapperError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// From the configuration: config::mapper_parameters (libcvo/config/mapper_parameters.hpp).
struct MapperParameters {
  loop_closure::LoopDetectorParameters detector;
  BackendParameters backend;
  core::LocalizationParameters localization;
};

/// A keyframe as the tracker sends it (CVO_KEYFRAME): frame.index is its frame in the session.
struct SessionKeyframe {
  core::SessionId session = 0;
  std::int64_t id = 0;
  const core::RgbdFrame& frame;
  core::SE3 odometry;  // T_odom_camera
  const registration::PointCloud& cloud;
  std::string_view robot = {};  // its tracker's (CVO_KEYFRAME's robot): the session's from its first keyframe
};

struct MapSession {
  core::SessionId session = 0;
  bool placed = false;        // in the map frame
  core::SessionId piece = 0;  // whose odometry frame its poses are in
  std::size_t keyframes = 0;
  std::int64_t joined_at_keyframe = -1;  // its newest keyframe id when it joined (first session: 0)
  core::SE3 correction;                  // T_piece_odom: piece pose = correction · odometry pose
  core::LocalizationState state = core::LocalizationState::kLocalizing;
  double last_match_time = -1;  // sensor time (s) of its newest keyframe with a verified match; -1: none
  double since_match_s = -1;    // its newest keyframe's time minus last_match_time; -1: no match
  bool visitor = false;         // localized in a read-only map: its keyframes are in no map
  // Of its newest keyframe's map pose (a visitor's window solve), [rho; phi], right-perturbed.
  std::optional<core::Matrix6d> keyframe_covariance = std::nullopt;
  std::int64_t covariance_keyframe = -1;  // the keyframe id it is of
  std::string robot = std::string();      // its tracker's (its keyframes name it); "": not known yet
};

struct MapKeyframe {
  core::SessionId session = 0;
  std::int64_t id = 0;
  double timestamp = 0;  // the keyframe's colour image time
  core::SE3 pose;        // T_piece_camera
};

struct MapLoop {
  core::SessionId from_session = 0, to_session = 0;
  std::int64_t from_id = 0, to_id = 0;        // keyframe ids in their sessions
  std::int64_t from_frame = 0, to_frame = 0;  // their frame indices in their sessions
  loop_closure::LoopClosure loop;             // node ids as the Backend holds them
  double chi2 = 0, weight = 1;                // at the current poses (Backend::loops)
};

/// One of a session's loops to a keyframe of another session, seen from the session's keyframe.
struct SessionLoop {
  std::int64_t keyframe = 0;  // the session's
  core::SessionId other_session = 0;
  std::int64_t other_keyframe = 0;
  core::SE3 measurement;  // T_keyframe^other
  core::SE3 other_pose;   // the other keyframe's pose (T_piece_camera, as MapKeyframe::pose)
};

/// One session's word, on its own (CVO_MAP_CORRECTION): its entry as map() has it, at the map's
/// revision, with its newest loops to other sessions.
struct SessionCorrection {
  std::uint64_t revision = 0;
  MapSession session;
  std::vector<SessionLoop> loops;  // newest first
};

struct Map {
  std::uint64_t revision = 0;
  std::vector<MapSession> sessions;    // in the order first seen
  std::vector<MapKeyframe> keyframes;  // by session (that order), then id
  std::vector<MapLoop> loops;          // in the order accepted
};

/// A keyframe merged into the earlier keyframe that covers it (README.md).
struct KeyframeMerge {
  core::SessionId session = 0;
  std::int64_t id = 0;
  std::int64_t frame = 0;  // the merged keyframe's frame index, colour time and odometry pose, so a
  double timestamp = 0;    // store can replay the merge without the keyframe's record
  core::SE3 odometry;
  core::SessionId covering_session = 0;
  std::int64_t covering_id = 0;
  core::SE3 relative;                                       // T_covering^id, the loop's measurement
  core::Matrix6d information = core::Matrix6d::Identity();  // the loop's
  double gamma = 0;                                         // its coverage γ
  // The keyframe's other verified loops, in the order entered: those that joined its session's
  // piece to the covering keyframe's (before the merge), and the rest (after it, as loops of c).
  std::vector<loop_closure::LoopClosure> joining, others;
};

/// A settled edge (Backend::settle) between two keyframes, named as the tracker names them: what a
/// store keeps of settled revisits.
struct SettledEdge {
  core::SessionId from_session = 0, to_session = 0;
  std::int64_t from_id = 0, to_id = 0;
  bool robust = false;    // of loops (a Cauchy kernel), else of local graphs
  core::SE3 measurement;  // T_from^to
  core::Matrix6d information = core::Matrix6d::Identity();
};

/// What settle() keeps of a session beyond its keyframes: how many it forgot (MapSession::keyframes
/// counts them) and its newest keyframe settled. A store keeps the newest.
struct SessionTally {
  core::SessionId session = 0;
  std::size_t forgotten = 0;
  std::int64_t settled_through = -1;
};

/// What one settle() did: the local graphs it settled and the keyframes it forgot (their records
/// are garbage now), and the settled edges and sessions' tallies that changed, as they are now.
struct Settlement {
  std::vector<std::pair<core::SessionId, std::int64_t>> graphs, keyframes;
  std::vector<SettledEdge> edges;
  std::vector<SessionTally> tallies;
  [[nodiscard]] bool empty() const { return graphs.empty() && keyframes.empty() && edges.empty(); }
};

/// What one add_keyframe did.
struct KeyframeOutcome {
  bool duplicate = false;               // the same keyframe again: nothing done
  std::size_t loops_tried = 0;          // candidates verified
  std::vector<MapLoop> loops;           // accepted
  std::vector<core::SessionId> joined;  // sessions placed in the map by it
  // Keyframes it merged (README.md: "Revisits"): itself (its loop is in `loops` only if it joined), and its
  // session's first keyframe, whose loops are searched once it has a successor.
  std::vector<KeyframeMerge> merges;
};

class Mapper {
 public:
  Mapper(loop_closure::Vocabulary vocabulary, const MapperParameters& parameters);

  /// Loops looked for, entered, optimised (README.md: "The mapper's calls"). Throws MapperError when (session, id) is
  /// known with another frame or pose (a repeat with the same frame index and pose is a duplicate), when id or the
  /// frame index is not above the session's previous keyframe's, when the frame index is 2^40 or more, and as
  /// LoopDetector::add_keyframe does on a bad frame (wrapped).
  KeyframeOutcome add_keyframe(const SessionKeyframe& keyframe);

  /// The closed local graph of keyframe (session, keyframe_id): its first node is that keyframe's
  /// frame when the keyframe is known. Returns the sessions it placed in the map (through loops
  /// that waited for it). Throws MapperError when it cannot be applied (as Backend does; a graph
  /// whose first frame is not its keyframe's).
  std::vector<core::SessionId> add_local_graph(core::SessionId session, std::int64_t keyframe_id,
                                               const odometry::LocalGraph& graph);

  /// The global optimisation of every frame, in at most max_seconds (Backend::optimise_all).
  posegraph::OptimizationReport finish(double max_seconds = std::numeric_limits<double>::infinity());

  /// From now on the map is read only and new sessions are localized in it (README.md).
  void localize_only();
  [[nodiscard]] bool localizing_only() const { return map_below_.has_value(); }
  /// The tracker's odometry of `session` failed (a new session follows): its state is kLost.
  void mark_lost(core::SessionId session);
  /// What map() says of one session, without building the map: a default entry (kLocalizing,
  /// unplaced) for one not seen.
  [[nodiscard]] MapSession session(core::SessionId session) const;
  /// session()'s robot alone ("" for one not seen or not named).
  [[nodiscard]] std::string robot(core::SessionId session) const;
  /// session(), at the map's revision, with the session's newest loops (at most max_loops) between
  /// its keyframes and keyframes of other sessions that are in the keyframe graph (map()'s loops).
  [[nodiscard]] SessionCorrection correction(core::SessionId session, std::size_t max_loops) const;
  /// Every session map() has an entry for, in its order.
  [[nodiscard]] std::vector<core::SessionId> sessions() const;
  /// map()'s revision.
  [[nodiscard]] std::uint64_t revision() const { return revision_ + backend_.revision(); }
  /// Optimisations of the keyframe graph so far (each may move every session's correction).
  [[nodiscard]] std::size_t optimisations() const { return optimisations_; }
  /// Factorisations of the keyframe graph for its marginal covariances so far.
  [[nodiscard]] std::size_t covariance_factorisations() const { return marginals_.factorisations(); }

  [[nodiscard]] Map map() const;
  /// The frames of one session (placed or not) in its piece's frame, stamped with their colour time.
  [[nodiscard]] core::Trajectory frame_trajectory(core::SessionId session) const;
  [[nodiscard]] bool placed(core::SessionId session) const { return backend_.placed(session); }
  [[nodiscard]] bool knows(core::SessionId session, std::int64_t keyframe_id) const;
  /// Keyframe (session, id) is known and merged into one covering it.
  [[nodiscard]] bool merged(core::SessionId session, std::int64_t keyframe_id) const;
  /// Keyframe (session, id) is known and has a pose in the keyframe graph: it is a node there, or an
  /// alias of one (merged). A keyframe whose local graph into it has not come yet is not held.
  [[nodiscard]] bool held(core::SessionId session, std::int64_t keyframe_id) const;

  [[nodiscard]] const Backend& backend() const { return backend_; }
  [[nodiscard]] std::size_t loops_tried() const { return loops_tried_; }
  [[nodiscard]] std::size_t loops_accepted() const { return loops_accepted_; }
  /// Keyframes merged into ones that cover them (README.md).
  [[nodiscard]] std::size_t merged_keyframes() const { return backend_.merged_keyframes(); }
  /// Applies a merge add_keyframe made before (a store's record): when keyframe (session, id) is
  /// known and merged so already, nothing (false); known and not merged, it is merged; not known
  /// (its record compacted away), it is registered from the merge alone, without images or loop
  /// detection, its other loops entered as add_keyframe entered them (then optimised likewise). Its frame must then be
  /// in the keyframe graph (the local graph ending at it applied) and free, the covering keyframe known and in the
  /// graph. Throws MapperError otherwise, nothing changed.
  bool apply_merge(const KeyframeMerge& merge);
  /// Settles merged keyframes older than their session's two newest (Backend::settle: their local
  /// graphs' frames go, and the keyframes once nothing names them: their records, loops and
  /// aliases), so that a map revisited for months holds what grows with its area (README.md).
  /// A service calls it after each keyframe or local graph; cvo-run, which writes every frame's
  /// pose, does not. A keyframe or local graph of a session at or below its newest settled keyframe
  /// that the mapper does not know is refused from then on (it was forgotten). Returns the keyframes
  /// forgotten by this call. Only a merged keyframe's graph to another merged keyframe settles: a
  /// graph into or out of the mapped area stays (it holds a kept keyframe's node for a replay).
  Settlement settle();
  /// A settled edge settle() reported (a store's record, replayed): Backend::apply_settled. Throws
  /// MapperError when an end is not a keyframe the mapper knows in the keyframe graph.
  void apply_settled(const SettledEdge& edge);
  /// A session's tally settle() reported (a store's record, replayed): it holds at least that.
  /// Throws MapperError for a session not seen.
  void apply_tally(const SessionTally& tally);
  /// Keyframes settle() forgot so far.
  [[nodiscard]] std::size_t forgotten_keyframes() const { return forgotten_keyframes_; }
  /// What is wrong with the mapper's bookkeeping, nullopt when nothing is: the Backend's
  /// (Backend::inconsistency: every alias names a node of the keyframe graph), and every keyframe
  /// recorded as merged is an alias there. Checked after every change in a debug build (NDEBUG
  /// off), where a break throws std::logic_error at its cause; tests call it.
  [[nodiscard]] std::optional<std::string> inconsistency() const;
  /// Keyframes held in visitors' windows, all visitors together (bounded: README.md).
  [[nodiscard]] std::size_t window_keyframes() const;

  static constexpr std::size_t kMaxWindows = 8;
  static constexpr std::size_t kMaxVisitors = 256;

 private:
  struct KeyframeRecord {
    std::int64_t frame = 0;  // index in its session
    double timestamp = 0;
    core::SE3 odometry;
    bool merged = false;  // into a keyframe that covers it (README.md)
  };
  struct Session {
    std::int64_t ordinal = 0;
    std::map<std::int64_t, KeyframeRecord> keyframes;  // by id
    std::int64_t joined_at_keyframe = -1;
    bool lost = false;
    double last_match_time = -1;
    std::vector<std::size_t> loops;     // keys in loops_ of its loops to other sessions, in order accepted
    std::set<std::int64_t> unsettled;   // merged keyframes not settled yet (settle())
    std::int64_t settled_through = -1;  // its newest keyframe settled
    std::size_t forgotten = 0;          // keyframes settle() forgot (MapSession::keyframes counts them)
    std::size_t forgotten_before = 0;   // by an earlier run: a stored tally's (no record of them is left)
    // Its first keyframe's id until its successor came: a first keyframe proposes no loop
    // candidates when it comes (no predecessor normalises η), its successor does (merge_first).
    std::optional<std::int64_t> undetected_first;
    std::string robot;  // from its first keyframe that names one
  };
  // A session localized in the read-only map.
  struct Visitor {
    std::int64_t ordinal = 0;
    std::uint64_t last_used = 0;  // the mapper's revision when it last had a keyframe
    std::deque<WindowKeyframe> window;
    std::vector<WindowMatch> matches;  // loops to the map from window keyframes
    std::optional<core::SE3> correction;
    std::optional<core::Matrix6d> covariance;
    std::int64_t covariance_keyframe = -1, localized_at_keyframe = -1;
    std::size_t keyframes = 0;
    double last_match_time = -1, newest_time = -1;
    bool lost = false;
    std::string robot;
  };

  Session& enter(core::SessionId id);
  KeyframeOutcome visit(const SessionKeyframe& keyframe);
  std::vector<loop_closure::LoopClosure> detect(const SessionKeyframe& keyframe,
                                                const loop_closure::KeyframePlacement& placement);
  void add_window_graph(Visitor& v, std::int64_t keyframe_id, const odometry::LocalGraph& graph);
  void move_window(Visitor& v);
  void solve(Visitor& v, std::int64_t newest_id);
  void forget_idle_visitors();
  [[nodiscard]] MapSession describe(core::SessionId id, const Visitor& v) const;
  [[nodiscard]] MapSession describe(core::SessionId id, const Session& s) const;
  // The session's newest keyframe in the keyframe graph: its id and node.
  [[nodiscard]] std::optional<std::pair<std::int64_t, posegraph::NodeId>> newest_in_graph(const Session& s) const;
  // Its marginal covariance, and the nodes every session's needs (newest keyframes, last nodes).
  [[nodiscard]] std::optional<core::Matrix6d> keyframe_covariance(posegraph::NodeId node) const;
  [[nodiscard]] std::vector<posegraph::NodeId> covariance_nodes() const;
  [[nodiscard]] posegraph::NodeId node(const Session& s, std::int64_t frame) const;
  [[nodiscard]] MapLoop describe(const loop_closure::LoopClosure& loop) const;
  std::vector<core::SessionId> after_change();  // optimise after new loops; note joins
  void check_in_debug() const;                  // inconsistency() as std::logic_error, unless NDEBUG
  // Of the new keyframe's loops (those that joined pieces entered already), the one to the keyframe
  // that covers it best, if any (README.md: "Revisits"), with its γ.
  std::optional<std::pair<std::size_t, double>> covering_loop(const std::vector<loop_closure::LoopClosure>& loops,
                                                              posegraph::NodeId keyframe, core::SessionId session);
  void merge(const KeyframeMerge& merge, posegraph::NodeId keyframe, posegraph::NodeId covering);
  bool merge_settled(const KeyframeMerge& merge, posegraph::NodeId keyframe, posegraph::NodeId covering);
  // A merge of keyframe (session, id) with its own fields filled in, the covering keyframe's not yet.
  [[nodiscard]] static KeyframeMerge merge_of(core::SessionId session, std::int64_t id, const KeyframeRecord& record);
  // A keyframe's verified loops and the views the estimate confirms (LoopDetector::last_confirmations).
  struct FoundLoops {
    std::vector<loop_closure::LoopClosure> loops, confirmations;
  };
  // Enters a keyframe's verified loops, those that join pieces first; merges it into the keyframe
  // that covers it best (by a loop or a confirmation), if one does: that merge (`keyframe`'s fields,
  // the covering keyframe's filled in).
  std::optional<KeyframeMerge> enter_loops(Session& s, KeyframeMerge keyframe, posegraph::NodeId node,
                                           const FoundLoops& found, KeyframeOutcome& outcome);
  // The session's first keyframe, once `next` (at node `next_node`, still in the loop detector: it
  // normalises η) follows it: its loops (LoopDetector::detect_first). merge_first enters them with
  // its merge only when one shows it covered, else none (so its merge record holds all they change).
  struct FirstLoops {
    std::int64_t id = 0;
    posegraph::NodeId node = 0;
    FoundLoops found;
  };
  std::optional<FirstLoops> first_loops(Session& s, std::int64_t next, posegraph::NodeId next_node);
  std::optional<KeyframeMerge> merge_first(Session& s, const FirstLoops& found);
  void enter_loop(Session& s, const loop_closure::LoopClosure& loop, double time, KeyframeOutcome& outcome);
  // A node Backend::settle forgot: its record and loops; its (session, id).
  std::optional<std::pair<core::SessionId, std::int64_t>> forget(posegraph::NodeId keyframe);
  [[nodiscard]] SettledEdge named(const posegraph::Edge& edge) const;

  loop_closure::LoopDetector detector_;
  Backend backend_;
  std::map<core::SessionId, Session> sessions_;
  std::vector<core::SessionId> order_;
  std::map<posegraph::NodeId, std::pair<core::SessionId, std::int64_t>> keyframe_of_node_;
  std::map<std::size_t, loop_closure::LoopClosure> loops_;  // by the order accepted (settle() forgets some)
  std::size_t loops_accepted_ = 0;
  std::size_t forgotten_keyframes_ = 0;
  std::size_t loops_tried_ = 0;
  std::uint64_t revision_ = 0;
  core::LocalizationParameters localization_;
  std::optional<posegraph::NodeId> map_below_;  // localize_only(): nodes below it are the map's
  std::map<core::SessionId, Visitor> visitors_;
  std::int64_t next_ordinal_ = 0;
  std::size_t optimisations_ = 0;
  // A cache: what map() and session() report does not depend on it, only what they cost.
  mutable KeyframeMarginals marginals_;
};

}  // namespace cvo::slam
