#pragma once
// What cvo-run measured over a run, and its two renderings: a human summary and one JSON object
// (the contract scripts read; see main.cpp).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "libcvo/eval/ate.hpp"
#include "libcvo/eval/rpe.hpp"
#include "program/json.hpp"

namespace cvo::tools {

struct FailedFrame {
  std::size_t index = 0;  // position in the sequence
  double timestamp = 0;   // colour stamp
  std::string stage;      // "read" (frame skipped), "selection" or "registration" (pose predicted)
  std::string reason;
};

/// An accepted loop after the final optimisation: its keyframes (frame indices within their
/// sessions, and the sessions: 1, 2, ... in folder order), χ² and the Cauchy kernel's weight (1:
/// fully trusted; near 0: treated as an outlier).
struct LoopEntry {
  std::int64_t from = 0, to = 0;
  double chi2 = 0, weight = 1;
  std::int64_t from_session = 1, to_session = 1;
};

/// One folder of a --mode slam run: a session of the map.
struct SessionEntry {
  std::string sequence;
  std::int64_t session = 0;
  std::size_t frames = 0, keyframes = 0;
  bool joined = false;                             // placed in the first session's map frame
  std::optional<std::int64_t> joined_at_keyframe;  // its keyframe id when it joined (first: 0)
};

/// What --mode slam adds: loops, the back end's time, and kf-cvo's own ATE on the same run.
/// What --map wrote (cvo-run --mode slam --map DIR).
struct MapReport {
  std::string dir;
  std::string up;  // which way up came from (mapping::up_source_name)
  int width = 0, height = 0;
  double resolution = 0;
  std::size_t occupied = 0, free = 0;  // cells
  std::size_t keyframes = 0;           // placed in the grid
  double bytes_per_keyframe = 0;       // local map (cloud and footprint)
  std::size_t cloud_points = 0;
  double place_ms = 0;                      // placing every local map at its final pose
  std::vector<double> keyframe_timestamps;  // of the keyframes in the map (their colour stamps), in map order
};

/// What --store wrote (cvo-run --mode slam --store FILE).
struct StoreReport {
  std::string file;
  std::uint64_t records = 0;  // keyframes and local graphs
  double ms = 0;              // encoding and writing them
};

struct SlamReport {
  std::size_t loops_accepted = 0;
  std::size_t loops_tried = 0;       // candidates verified (matches, RANSAC, CVO, α)
  std::size_t keyframes_merged = 0;  // into earlier keyframes covering them (slam/mapper.hpp)
  std::size_t graph_nodes = 0;       // of the keyframe graph, at the end
  std::size_t graph_edges = 0;
  double backend_ms = 0;                        // local graphs, loop detection, keyframe optimisations
  double final_optimisation_ms = 0;             // the last local graph and the global optimisation
  std::optional<eval::AteResult> ate_odometry;  // of the tracker's poses, before the back end
  std::vector<LoopEntry> loops;                 // in acceptance order
  std::vector<SessionEntry> sessions;           // one per folder, in order
  std::optional<MapReport> map;
  std::optional<StoreReport> store;
};

/// What --mode localize adds (localize.hpp): frames counted by the state of their session when
/// they were tracked (a lost frame: the one whose odometry failed, which ended its session).
struct LocalizeReport {
  std::string map_store;
  std::size_t sessions = 0;  // started in the run: 1 + the frames lost
  std::size_t frames_localizing = 0, frames_localized = 0, frames_lost = 0;
  std::optional<double> localized_after_s;  // sensor time from the first frame to the first localized one
  std::size_t relocalizations = 0;          // sessions localized after an earlier one of the run was
  std::size_t window_keyframes_max = 0;     // the most keyframes the localization window held (Mapper)
};

struct RunReport {
  std::string mode;
  std::string sequence, trajectory;
  std::string groundtruth;    // where the ground truth came from; empty when there was none
  std::size_t frames = 0;     // frames of the sequence attempted, unreadable ones included
  std::size_t poses = 0;      // lines written to the trajectory
  std::size_t keyframes = 0;  // 0 in frame-to-frame mode, which has no keyframes
  std::vector<FailedFrame> failed;
  std::vector<double> track_ms;            // whole track() step, per frame tracked
  std::vector<double> points;              // selected per frame tracked
  std::vector<double> iterations;          // per registration run
  double wall_s = 0;                       // the whole loop, reading images included
  std::optional<eval::AteResult> ate;      // with ground truth (and >= 3 associated poses)
  std::optional<eval::RpeResult> rpe;      // with ground truth (and >= 2 pairs 1 s apart)
  std::optional<SlamReport> slam;          // --mode slam only
  std::optional<LocalizeReport> localize;  // --mode localize only
};

void print_text(std::FILE* out, const RunReport& report);
program::Json to_json(const RunReport& report);

}  // namespace cvo::tools
