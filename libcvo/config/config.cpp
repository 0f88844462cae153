#include "libcvo/config/config.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <type_traits>
#include <utility>
#include <variant>

#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include "libcvo/core/session.hpp"
#include "libcvo/io/numbers.hpp"

namespace cvo::config {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Shortest text that reads back to the same double ("0.1", "1e-05").
std::string shortest(double v) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, v).ptr;
  return {buffer, end};
}

// The valid values of a numeric key.
struct Range {
  double lo = -kInf, hi = kInf;
  bool lo_open = false, hi_open = false;

  [[nodiscard]] bool contains(double v) const { return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi); }
  [[nodiscard]] std::string text() const {
    if (hi == kInf) return (lo_open ? "> " : ">= ") + shortest(lo);
    return std::string("in ").append(lo_open ? "(" : "[") + shortest(lo) + ", " + shortest(hi) + (hi_open ? ")" : "]");
  }
};

constexpr Range kAny{};
constexpr Range kPositive{0, kInf, true, false};
constexpr Range kNonNegative{0, kInf};
constexpr Range kAtLeastOne{1, kInf};
constexpr Range kUnit{0, 1};                      // [0, 1]
constexpr Range kUnitNonZero{0, 1, true, false};  // (0, 1]
constexpr Range kHalfTurnDeg{0, 180, true, false};
constexpr Range kThreads{1, 1024};
constexpr Range kAtLeastTwo{2, kInf};
constexpr Range kAtLeastThree{3, kInf};
constexpr Range kAboveOne{1, kInf, true, false};
constexpr Range kHalfTurnDegOrZero{0, 180};
constexpr Range kUint32{0, 4294967295.0};
constexpr Range kHalfToOne{0.5, 1, true, true};
constexpr Range kZeroToHalf{0, 0.5, true, true};

template <class T>
using Get = std::function<T&(Config&)>;

// A pose key: none, or [x, y, z, qx, qy, qz, qw].
using Pose = std::optional<core::PoseParameter>;

// "none", or 7 numbers separated by commas or blanks, in brackets or not; the quaternion must be
// unit length to 1e-6 (a pose typed by hand is checked, not silently normalised).
std::string parse_pose(std::string_view text, Pose& pose) {
  if (text == "none" || text == "null" || text == "~") return pose.reset(), std::string{};
  std::string s(text);
  if (s.size() >= 2 && s.front() == '[' && s.back() == ']') s = s.substr(1, s.size() - 2);
  std::replace(s.begin(), s.end(), ',', ' ');
  std::istringstream in(s);
  core::PoseParameter values{};
  std::size_t n = 0;
  for (std::string word; in >> word; ++n) {
    const auto v = io::to_finite(word);
    if (!v || n >= values.size()) return "expected none or [x, y, z, qx, qy, qz, qw], got '" + std::string(text) + "'";
    values[n] = *v;
  }
  if (n != values.size()) return "expected none or [x, y, z, qx, qy, qz, qw], got '" + std::string(text) + "'";
  const double norm2 = values[3] * values[3] + values[4] * values[4] + values[5] * values[5] + values[6] * values[6];
  if (std::abs(norm2 - 1.0) > 2e-6)
    return "the quaternion qx qy qz qw must have unit length, got '" + std::string(text) + "'";
  pose = values;
  return {};
}

// One row of the table: everything the loader, the overrides and the dump know about a key.
struct Field {
  std::string key;  // "section.member", or "member" at the top level
  std::variant<Get<double>, Get<int>, Get<std::size_t>, Get<std::uint32_t>, Get<bool>, Get<std::string>, Get<Pose>>
      member;
  Range range;           // numeric keys only
  std::string_view doc;  // the dump's comment: paper symbol and meaning
};

template <class S, class T>
Field row(std::string key, S Config::*section, T S::*member, Range range, std::string_view doc) {
  return {std::move(key), Get<T>([=](Config& c) -> T& { return (c.*section).*member; }), range, doc};
}

using core::CvoParameters, core::SelectionParameters, core::KeyframeParameters, core::LoopClosureParameters,
    core::PoseGraphParameters, core::DatasetParameters, core::OdometryParameters, core::KeyframeTrackingParameters,
    core::LoopVerificationParameters;
using core::LocalizationParameters, core::MappingParameters;

constexpr Range kRealtimePriority{0, 99};  // SCHED_FIFO priorities; 0 = do not ask for one
constexpr Range kCpu{-1, 4095};            // -1 = no affinity

// Sections must stay contiguous: the dump opens a section where the prefix changes.
const std::vector<Field>& table() {
  static const std::vector<Field> fields{
      row("selection.target_points", &Config::selection, &SelectionParameters::target_points, kAtLeastOne,
          "points selected per 640x480 frame (paper section 6)"),
      row("selection.min_depth_m", &Config::selection, &SelectionParameters::min_depth_m, kNonNegative,
          "nearest depth used (m)"),
      row("selection.max_depth_m", &Config::selection, &SelectionParameters::max_depth_m, kPositive,
          "farthest depth used (m)"),
      row("selection.gradient_weight", &Config::selection, &SelectionParameters::gradient_weight, kNonNegative,
          "scale of the gradient part of a point's label (0: RGB only)"),
      row("selection.depth_time_offset_s", &Config::selection, &SelectionParameters::depth_time_offset_s, kAny,
          "depth taken at its stamp plus this, relative to colour stamps (s); KF-CVO depth-time compensation"),
      row("selection.depth_window", &Config::selection, &SelectionParameters::depth_window, kNonNegative,
          "a point's depth is the mean over the (2r+1)^2 pixels around it on its surface (0: its pixel's own)"),
      row("selection.depth_window_tolerance", &Config::selection, &SelectionParameters::depth_window_tolerance,
          kNonNegative, "a window pixel is on the point's surface within this fraction of its depth"),
      row("cvo.ell_init", &Config::cvo, &CvoParameters::ell_init, kPositive,
          "ℓ_init, initial spatial kernel length-scale (m)"),
      row("cvo.ell_min", &Config::cvo, &CvoParameters::ell_min, kPositive,
          "smallest spatial length-scale of the schedule (m)"),
      row("cvo.ell_decay", &Config::cvo, &CvoParameters::ell_decay, kUnitNonZero,
          "factor applied to ℓ as the solver converges"),
      row("cvo.sigma", &Config::cvo, &CvoParameters::sigma, kPositive,
          "σ, spatial kernel signal (std. dev.; amplitude σ²)"),
      row("cvo.ell_color", &Config::cvo, &CvoParameters::ell_color, kPositive, "ℓ_c, colour kernel length-scale"),
      row("cvo.sigma_color", &Config::cvo, &CvoParameters::sigma_color, kPositive,
          "σ_c, colour kernel signal (std. dev.; amplitude σ_c²)"),
      row("cvo.sparsification_threshold", &Config::cvo, &CvoParameters::sparsification_threshold, kNonNegative,
          "kernel products below this are dropped"),
      row("cvo.max_iterations", &Config::cvo, &CvoParameters::max_iterations, kAtLeastOne,
          "solver iterations per registration"),
      row("cvo.min_step", &Config::cvo, &CvoParameters::min_step, kPositive,
          "converged when |Δρ| + |Δφ| (m + rad) is below this at ℓ_min"),
      row("cvo.threads", &Config::cvo, &CvoParameters::threads, kThreads, "tracker threads"),
      row("cvo.mutual_visibility", &Config::cvo, &CvoParameters::mutual_visibility, kAny,
          "registration sums only points each view sees (no pull from the image borders)"),
      row("odometry.max_points", &Config::odometry, &OdometryParameters::max_points, kAtLeastOne,
          "capacity of each point cloud (trackers, loop detector); a larger selection is clamped"),
      row("odometry.restart_after_failures", &Config::odometry, &OdometryParameters::restart_after_failures,
          kAtLeastOne, "cvo, opencv-*: failed frames in a row after which the failed frame becomes the reference"),
      row("keyframe.inner_product_ratio_threshold", &Config::keyframe,
          &KeyframeParameters::inner_product_ratio_threshold, kUnit, "γ_thres, new keyframe below this ratio (eq. 10)"),
      row("keyframe.translation_threshold_m", &Config::keyframe, &KeyframeParameters::translation_threshold_m,
          kPositive, "t_thres, new keyframe beyond this translation (m)"),
      row("keyframe.rotation_threshold_deg", &Config::keyframe, &KeyframeParameters::rotation_threshold_deg,
          kHalfTurnDeg, "θ_thres, new keyframe beyond this rotation (degrees)"),
      row("keyframe.local_graph_capacity", &Config::keyframe_tracking,
          &KeyframeTrackingParameters::local_graph_capacity, kAtLeastTwo,
          "frames per keyframe (its local graph) before a new keyframe is forced"),
      row("keyframe.gamma_ell", &Config::keyframe_tracking, &KeyframeTrackingParameters::gamma_ell, kPositive,
          "spatial length-scale of γ's inner products (m)"),
      row("keyframe.gamma_sigma", &Config::keyframe_tracking, &KeyframeTrackingParameters::gamma_sigma, kPositive,
          "spatial signal of γ's inner products (std. dev.), looser than cvo.sigma so γ is smooth"),
      row("keyframe.gamma_stride", &Config::keyframe_tracking, &KeyframeTrackingParameters::gamma_stride, kAtLeastOne,
          "γ's inner products sum every stride-th point of the frame (1: all)"),
      row("keyframe.chain_weight", &Config::keyframe_tracking, &KeyframeTrackingParameters::chain_weight, kNonNegative,
          "scale of the chain edge's information in the fused pose (0: keyframe registration alone)"),
      row("keyframe.chain_full_weight_deg", &Config::keyframe_tracking,
          &KeyframeTrackingParameters::chain_full_weight_deg, kHalfTurnDegOrZero,
          "rotation from the keyframe (degrees) at which the chain weight, ramped as θ², is full (0: always full)"),
      row("keyframe.max_turn_rate_deg_s", &Config::keyframe_tracking, &KeyframeTrackingParameters::max_turn_rate_deg_s,
          kNonNegative, "fastest turn (deg/s) a session's first pair of frames is registered across (0: ℓ_init)"),
      row("loop_closure.similarity_threshold", &Config::loop_closure, &LoopClosureParameters::similarity_threshold,
          kUnit, "η_thres, normalised bag-of-words score"),
      row("loop_closure.match_ratio", &Config::loop_closure, &LoopClosureParameters::match_ratio, kUnitNonZero,
          "best / second-best descriptor distance"),
      row("loop_closure.min_matches", &Config::loop_closure, &LoopClosureParameters::min_matches, kAtLeastOne,
          "descriptor matches needed for a loop candidate"),
      row("loop_closure.max_refinements", &Config::loop_verification, &LoopVerificationParameters::max_refinements,
          kNonNegative, "CVO refinements per new keyframe, best η first (0: no limit)"),
      row("loop_closure.ransac_iterations", &Config::loop_verification, &LoopVerificationParameters::ransac_iterations,
          kAtLeastOne, "RANSAC minimal sets tried for the initial pose"),
      row("loop_closure.ransac_inlier_m", &Config::loop_verification, &LoopVerificationParameters::ransac_inlier_m,
          kPositive, "3-D distance within which a match is a RANSAC inlier (m)"),
      row("loop_closure.min_inliers", &Config::loop_verification, &LoopVerificationParameters::min_inliers,
          kAtLeastThree, "RANSAC inliers needed for an initial pose"),
      row("loop_closure.min_inlier_retention", &Config::loop_verification,
          &LoopVerificationParameters::min_inlier_retention, kUnit,
          "share of RANSAC's inliers the CVO pose must keep within ransac_inlier_m"),
      row("loop_closure.ransac_seed", &Config::loop_verification, &LoopVerificationParameters::ransac_seed, kUint32,
          "seed of RANSAC's random generator: the same loops on every run"),
      row("loop_closure.orb_features", &Config::loop_verification, &LoopVerificationParameters::orb_features,
          kAtLeastOne,
          "ORB keypoints per keyframe at most, the strongest first (the default vocabulary was "
          "trained with the orb_* defaults)"),
      row("loop_closure.orb_scale_factor", &Config::loop_verification, &LoopVerificationParameters::orb_scale_factor,
          kAboveOne, "ORB pyramid scale between levels"),
      row("loop_closure.orb_levels", &Config::loop_verification, &LoopVerificationParameters::orb_levels, kAtLeastOne,
          "ORB pyramid levels"),
      row("loop_closure.orb_edge_threshold", &Config::loop_verification,
          &LoopVerificationParameters::orb_edge_threshold, kNonNegative,
          "ORB border without features (pixels; at least the patch size, 31, so descriptors fit)"),
      row("loop_closure.orb_fast_threshold", &Config::loop_verification,
          &LoopVerificationParameters::orb_fast_threshold, kAtLeastOne, "ORB's FAST intensity threshold"),
      row("pose_graph.cauchy_delta", &Config::pose_graph, &PoseGraphParameters::cauchy_delta, kPositive,
          "δ of the Cauchy loss ρ(x) = δ² log(1 + x/δ²)"),
      row("pose_graph.bridge_information", &Config::pose_graph, &PoseGraphParameters::bridge_information, kPositive,
          "information (times I) of the edge bridging a tracking restart, per unit (σ ~ 1 m, 1 rad)"),
      row("pose_graph.max_iterations", &Config::pose_graph, &PoseGraphParameters::max_iterations, kAtLeastOne,
          "Levenberg-Marquardt iterations per optimisation"),
      row("dataset.max_association_dt", &Config::dataset, &DatasetParameters::max_association_dt, kPositive,
          "colour-depth timestamp association window (s)"),
      row("mapping.cell_size", &Config::mapping, &MappingParameters::cell_size, kPositive,
          "occupancy grid cell and OctoMap voxel edge (m)"),
      row("mapping.voxel_size", &Config::mapping, &MappingParameters::voxel_size, kPositive,
          "coloured cloud voxel edge (m)"),
      row("mapping.obstacle_min_height", &Config::mapping, &MappingParameters::obstacle_min_height, kNonNegative,
          "points lower than this above the floor are floor (m)"),
      row("mapping.obstacle_max_height", &Config::mapping, &MappingParameters::obstacle_max_height, kPositive,
          "points higher than this above the floor are no obstacle (m)"),
      row("mapping.max_range", &Config::mapping, &MappingParameters::max_range, kPositive,
          "depth beyond this is not mapped (m)"),
      row("mapping.pixel_stride", &Config::mapping, &MappingParameters::pixel_stride, kAtLeastOne,
          "every stride-th pixel of each row and column is mapped"),
      row("mapping.hit_probability", &Config::mapping, &MappingParameters::hit_probability, kHalfToOne,
          "occupancy probability a keyframe that sees a surface in a cell gives it"),
      row("mapping.miss_probability", &Config::mapping, &MappingParameters::miss_probability, kZeroToHalf,
          "occupancy probability a keyframe whose rays cross a cell gives it"),
      Field{"mapping.base_T_camera", Get<Pose>([](Config& c) -> Pose& { return c.mapping.base_T_camera; }), kAny,
            "the camera's pose on a base with z up, origin on the floor: x, y, z, qx, qy, qz, qw (none: gravity "
            "from the recording's accelerometer, else the floor plane)"},
      row("localization.window_keyframes", &Config::localization, &LocalizationParameters::window_keyframes,
          kAtLeastTwo, "a session being localized in a stored map keeps its newest keyframes, this many"),
      row("trackerd.source", &Config::trackerd, &TrackerdParameters::source, kAny,
          "frame source: tum:DIR, lcm:URL, openni2:URI (openni2:any), v4l2:COLOUR,DEPTH"),
      row("trackerd.lcm_url", &Config::trackerd, &TrackerdParameters::lcm_url, kAny,
          "LCM provider the results are published on (ttl=0: never leaves the host)"),
      row("trackerd.paced", &Config::trackerd, &TrackerdParameters::paced, kAny,
          "tum: sources play at their recorded rate (false: as fast as possible)"),
      row("trackerd.exit_on_eof", &Config::trackerd, &TrackerdParameters::exit_on_eof, kAny,
          "exit 0 when a finite source (folder, log, .oni) ends, after tracking every frame"),
      row("trackerd.ring_slots", &Config::trackerd, &TrackerdParameters::ring_slots, kAtLeastOne,
          "preallocated frames between acquisition and tracking; when full the oldest is dropped"),
      row("trackerd.deterministic", &Config::trackerd, &TrackerdParameters::deterministic, kAny,
          "never drop: acquisition waits for the tracker, so a replay gives the same poses every time"),
      row("trackerd.realtime_priority", &Config::trackerd, &TrackerdParameters::realtime_priority, kRealtimePriority,
          "SCHED_FIFO priority of the tracking thread (0: normal scheduling)"),
      row("trackerd.cpu", &Config::trackerd, &TrackerdParameters::cpu, kCpu,
          "CPU the tracking thread is pinned to (-1: any)"),
      row("trackerd.lock_memory", &Config::trackerd, &TrackerdParameters::lock_memory, kAny,
          "mlockall: no page faults in the tracking thread"),
      row("trackerd.deadline_ms", &Config::trackerd, &TrackerdParameters::deadline_ms, kPositive,
          "a frame whose receipt-to-pose latency exceeds this is a deadline miss"),
      row("trackerd.warmup_frames", &Config::trackerd, &TrackerdParameters::warmup_frames, kNonNegative,
          "frames after which the tracking thread must not allocate (counted in CVO_STATUS)"),
      row("trackerd.keyframe_colour_encoding", &Config::trackerd, &TrackerdParameters::keyframe_colour_encoding, kAny,
          "colour image encoding of CVO_KEYFRAME: raw, jpeg or png"),
      row("trackerd.keyframe_transport", &Config::trackerd, &TrackerdParameters::keyframe_transport, kAny,
          "how keyframes and local graphs go out: chunks (slices of one datagram each on CVO_KEYFRAME_CHUNK, a lost "
          "packet costs a slice), whole (CVO_KEYFRAME, CVO_LOCAL_GRAPH), or auto (whole into a file:// log, chunks "
          "on a network)"),
      row("trackerd.status_period_s", &Config::trackerd, &TrackerdParameters::status_period_s, kPositive,
          "CVO_STATUS period"),
      row("trackerd.keyframe_history", &Config::trackerd, &TrackerdParameters::keyframe_history, kNonNegative,
          "last keyframes and their local graphs kept to send again when the back end asks (CVO_KEYFRAME_REQUEST); "
          "each preallocated, about 2.2 MB at 640x480; 0: none"),
      row("trackerd.resend_bytes_per_s", &Config::trackerd, &TrackerdParameters::resend_bytes_per_s, kPositive,
          "bytes a second that CVO_KEYFRAME_REQUESTs may make the tracker send again, per requester and per session "
          "(a burst of one second's worth); beyond it a keyframe waits for a later request"),
      row("trackerd.camera_change_frames", &Config::trackerd, &TrackerdParameters::camera_change_frames, kAtLeastOne,
          "frames of another camera (size or intrinsics) in a row that make the tracker re-initialise for it in a "
          "new session; fewer are refused"),
      row("trackerd.max_map_jump_m", &Config::trackerd, &TrackerdParameters::max_map_jump_m, kPositive,
          "a CVO_MAP correction that moves the map frame further than this (m) from the last one applied is refused"),
      row("trackerd.max_map_jump_deg", &Config::trackerd, &TrackerdParameters::max_map_jump_deg, kHalfTurnDeg,
          "a CVO_MAP correction that turns the map frame further than this (degrees) from the last one applied is "
          "refused"),
      row("trackerd.map_epoch_slack_s", &Config::trackerd, &TrackerdParameters::map_epoch_slack_s, kNonNegative,
          "a CVO_MAP whose epoch (its back end's start) lies further than this (s) in the future of this clock is "
          "refused: clocks of one deployment agree within it"),
      row("trackerd.map_revisions_per_s", &Config::trackerd, &TrackerdParameters::map_revisions_per_s, kPositive,
          "a CVO_MAP revision further ahead of the applied one than this many per second since then (at least one "
          "second's worth) is refused: a back end revises its map at a bounded rate"),
      row("trackerd.map_pose_until_localized", &Config::trackerd, &TrackerdParameters::map_pose_until_localized, kAny,
          "map pose published before the back end localizes the session: odometry or none"),
      row("trackerd.robot", &Config::trackerd, &TrackerdParameters::robot, kAny,
          "the robot this tracker speaks for, in its messages; $HOSTNAME: the host's name"),
      row("trackerd.spool", &Config::trackerd, &TrackerdParameters::spool, kAny,
          "directory where keyframes and local graphs wait until the back end acknowledges them, so that a tracker "
          "started again after a crash or power cut hands them over (none: no spool)"),
      row("trackerd.spool_bytes", &Config::trackerd, &TrackerdParameters::spool_bytes, kAtLeastOne,
          "the spool's bound in bytes: past it the oldest messages go first"),
      row("trackerd.linger_s", &Config::trackerd, &TrackerdParameters::linger_s, kNonNegative,
          "at a clean exit, seconds the tracker waits at most for the back end to acknowledge every keyframe it "
          "published (sending again what is missing), then names what was not (0: does not wait)"),
      row("backendd.lcm_url", &Config::backendd, &BackenddParameters::lcm_url, kAny,
          "LCM provider keyframes and local graphs come from, and CVO_MAP goes to"),
      row("backendd.store", &Config::backendd, &BackenddParameters::store, kAny,
          "append-only keyframe store: a restart resumes with every keyframe received"),
      row("backendd.vocabulary", &Config::backendd, &BackenddParameters::vocabulary, kAny,
          "ORB vocabulary file, or default (the one installed with cvo-slam)"),
      row("backendd.status_period_s", &Config::backendd, &BackenddParameters::status_period_s, kPositive,
          "CVO_STATUS period; each live session's CVO_MAP_CORRECTION goes out again at least this often"),
      row("backendd.map_period_s", &Config::backendd, &BackenddParameters::map_period_s, kNonNegative,
          "the full CVO_MAP goes out at most this often (s) while the map changes, at once after a "
          "join, a second after the last after a loop closure, and at the stop (changed sessions' CVO_MAP_CORRECTIONs "
          "after every change); 0: after every "
          "change"),
      row("backendd.stop_timeout_s", &Config::backendd, &BackenddParameters::stop_timeout_s, kNonNegative,
          "a SIGTERM/SIGINT stop ends within this (s), below the unit's TimeoutStopSec: records still waiting stay "
          "in the store for the next start, the final optimisation gets the time left"),
      row("backendd.publish_url", &Config::backendd, &BackenddParameters::publish_url, kAny,
          "LCM provider CVO_MAP and CVO_STATUS go to; lcm_url: the same one (set it when lcm_url is a file:// log)"),
      row("backendd.exit_on_eof", &Config::backendd, &BackenddParameters::exit_on_eof, kAny,
          "exit 0 when a file:// lcm_url ends, after the final optimisation and the final map"),
      row("backendd.queue_max", &Config::backendd, &BackenddParameters::queue_max, kAtLeastOne,
          "received records waiting for the back end in memory; beyond it a live message waits in the store, "
          "a log waits"),
      row("backendd.unsaved_records_max", &Config::backendd, &BackenddParameters::unsaved_records_max, kNonNegative,
          "records held in memory while the store cannot be written (disk full), saved in order when it can; "
          "beyond it a record is used but lost on restart"),
      row("backendd.max_records_per_session", &Config::backendd, &BackenddParameters::max_records_per_session,
          kAtLeastOne,
          "keyframes and local graphs one tracker session may store; past it its records are refused (BAD_QUOTA)"),
      row("backendd.max_records_per_sender", &Config::backendd, &BackenddParameters::max_records_per_sender,
          kAtLeastOne,
          "keyframes and local graphs one sender (a tracker daemon, all its sessions; on an open bus everyone) may "
          "store; past it its records are refused (BAD_QUOTA)"),
      row("backendd.mode", &Config::backendd, &BackenddParameters::mode, kAny,
          "mapping (every session grows the stored map) or localization (the stored map is read only; sessions "
          "are localized in it, never stored)"),
      row("auth.key_file", &Config::auth, &AuthParameters::key_file, kAny,
          "the deployment key file (cvo-keygen, mode 0600; under systemd $CREDENTIALS_DIRECTORY/cvo-slam.key): every "
          "message sent is signed and every one received verified; none: an open bus"),
      row("auth.max_age_s", &Config::auth, &AuthParameters::max_age_s, kPositive,
          "a message whose counter (its sender's clock) is older than this by the receiver's clock is refused as "
          "a replay (s); clocks must agree within it"),
      Field{"camera", Get<std::string>([](Config& c) -> std::string& { return c.camera; }), kAny,
            "tum_fr1, tum_fr2, tum_fr3, synthetic, or a path to an intrinsics file"},
  };
  return fields;
}

const Field* find_field(std::string_view key) {
  for (const auto& f : table())
    if (f.key == key) return &f;
  return nullptr;
}

std::string_view section_of(std::string_view key) {
  const auto dot = key.find('.');
  return dot == std::string_view::npos ? std::string_view{} : key.substr(0, dot);
}

bool is_section(std::string_view name) {
  return std::any_of(table().begin(), table().end(), [&](const Field& f) { return section_of(f.key) == name; });
}

// Sets the field from its text; returns what is wrong with the text, or "" when it was set.
std::string assign(const Field& field, Config& config, std::string_view text) {
  // Built with append(): GCC 12 warns falsely (-Wrestrict) on "'" + std::string(...).
  const std::string quoted = std::string("'").append(text).append("'");
  return std::visit(
      [&](const auto& get) -> std::string {
        using T = std::remove_reference_t<decltype(get(config))>;
        if constexpr (std::is_same_v<T, Pose>) {
          return parse_pose(text, get(config));
        } else if constexpr (std::is_same_v<T, std::string>) {
          if (text.empty()) return "must not be empty";
          get(config) = std::string(text);
          return {};
        } else if constexpr (std::is_same_v<T, bool>) {
          const auto v = io::to_bool(text);
          if (!v) return "expected true or false, got " + quoted;
          get(config) = *v;
          return {};
        } else if constexpr (std::is_same_v<T, double>) {
          const auto v = io::to_finite(text);
          if (!v) return "expected a finite number, got " + quoted;
          if (!field.range.contains(*v)) return "must be " + field.range.text() + ", got " + quoted;
          get(config) = *v;
          return {};
        } else {
          const auto v = io::to_integer(text);
          if (!v) return "expected an integer, got " + quoted;
          if (!field.range.contains(static_cast<double>(*v)))
            return "must be " + field.range.text() + ", got " + quoted;
          if (!std::in_range<T>(*v)) return "out of range: " + quoted;
          get(config) = static_cast<T>(*v);
          return {};
        }
      },
      field.member);
}

std::string kind_of(const Field& field) {
  return std::visit(
      [](const auto& get) -> std::string {
        using T = std::remove_reference_t<std::invoke_result_t<decltype(get), Config&>>;
        if constexpr (std::is_same_v<T, Pose>)
          return "none or [x, y, z, qx, qy, qz, qw]";
        else if constexpr (std::is_same_v<T, std::string>)
          return "a string";
        else if constexpr (std::is_same_v<T, bool>)
          return "true or false";
        else if constexpr (std::is_same_v<T, double>)
          return "a number";
        else
          return "an integer";
      },
      field.member);
}

std::string format_value(const Field& field, Config& config) {
  return std::visit(
      [&](const auto& get) -> std::string {
        const auto& v = get(config);
        using T = std::remove_cvref_t<decltype(v)>;
        if constexpr (std::is_same_v<T, Pose>) {
          if (!v) return "none";
          std::string text = "[";
          for (std::size_t i = 0; i < v->size(); ++i) text.append(i ? ", " : "").append(shortest((*v)[i]));
          return text + "]";
        } else if constexpr (std::is_same_v<T, std::string>) {
          YAML::Emitter out;  // quotes the string when YAML needs it
          out << v;
          return out.c_str();
        } else if constexpr (std::is_same_v<T, bool>) {
          return v ? "true" : "false";
        } else if constexpr (std::is_same_v<T, double>) {
          return shortest(v);
        } else {
          return std::to_string(v);
        }
      },
      field.member);
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// " (did you mean X?)" for a misspelt key or one put in the wrong section; "" when nothing is close.
std::string suggestion(std::string_view typed, const std::vector<std::string>& candidates) {
  if (const auto dot = typed.rfind('.'); dot != std::string_view::npos) {
    const auto member = typed.substr(dot);  // ".ell_init"
    for (const auto& c : candidates)
      if (c.ends_with(member)) return " (did you mean " + c + "?)";
  }
  const std::string* best = nullptr;
  std::size_t best_distance = std::max<std::size_t>(2, typed.size() / 4) + 1;
  for (const auto& c : candidates)
    if (const auto d = edit_distance(typed, c); d < best_distance) best = &c, best_distance = d;
  return best ? " (did you mean " + *best + "?)" : "";
}

std::vector<std::string> top_level_names() {
  std::vector<std::string> names;
  for (const auto& f : table()) {
    const auto name = std::string(section_of(f.key).empty() ? std::string_view(f.key) : section_of(f.key));
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  return names;
}

// Constraints between keys, which no single row can check.
void check_consistency(const Config& c, const std::filesystem::path& source) {
  if (c.selection.min_depth_m >= c.selection.max_depth_m)
    throw ConfigError(source, "selection.min_depth_m (" + shortest(c.selection.min_depth_m) +
                                  ") must be below selection.max_depth_m (" + shortest(c.selection.max_depth_m) + ")");
  if (c.mapping.obstacle_min_height >= c.mapping.obstacle_max_height)
    throw ConfigError(source, "mapping.obstacle_min_height (" + shortest(c.mapping.obstacle_min_height) +
                                  ") must be below mapping.obstacle_max_height (" +
                                  shortest(c.mapping.obstacle_max_height) + ")");
  // A keyframe's footprint is a lattice of half-cells out to max_range (libcvo/mapping/local_map.hpp).
  if (c.mapping.max_range > 4000 * c.mapping.cell_size)
    throw ConfigError(source, "mapping.max_range (" + shortest(c.mapping.max_range) +
                                  ") must be at most 4000 mapping.cell_size (" + shortest(c.mapping.cell_size) + ")");
  if (const auto& t = c.trackerd.keyframe_transport; t != "auto" && t != "chunks" && t != "whole")
    throw ConfigError(source, "trackerd.keyframe_transport (" + t + ") must be auto, chunks or whole");
  if (c.trackerd.map_pose_until_localized != "odometry" && c.trackerd.map_pose_until_localized != "none")
    throw ConfigError(source, "trackerd.map_pose_until_localized (" + c.trackerd.map_pose_until_localized +
                                  ") must be odometry or none");
  if (c.trackerd.robot != kHostName && !core::is_robot_name(c.trackerd.robot))
    throw ConfigError(source, "trackerd.robot (" + c.trackerd.robot + ") must be $HOSTNAME or " +
                                  std::string(core::kRobotNameRule) + " (a host name's)");
  if (c.backendd.mode != "mapping" && c.backendd.mode != "localization")
    throw ConfigError(source, "backendd.mode (" + c.backendd.mode + ") must be mapping or localization");
  if (c.cvo.ell_min > c.cvo.ell_init)
    throw ConfigError(source, "cvo.ell_min (" + shortest(c.cvo.ell_min) + ") must not exceed cvo.ell_init (" +
                                  shortest(c.cvo.ell_init) + ")");
}

std::size_t line_of(const YAML::Mark& mark) { return mark.line >= 0 ? static_cast<std::size_t>(mark.line) + 1 : 0; }

std::string node_kind(const YAML::Node& node) {
  if (node.IsMap()) return "a mapping";
  if (node.IsSequence()) return "a sequence";
  return "nothing";
}

// Errors point at the key's line: a missing value has no place of its own.
void set_from_node(const Field& field, const YAML::Node& value, std::size_t line, Config& config,
                   const std::filesystem::path& source) {
  std::string text;
  if (value.IsSequence() && std::holds_alternative<Get<Pose>>(field.member)) {
    for (const auto& element : value) {
      if (!element.IsScalar())
        throw ConfigError(source, line,
                          field.key + ": expected " + kind_of(field) + ", got a nested " + node_kind(element));
      text.append(text.empty() ? "" : " ").append(element.Scalar());
    }
  } else if (value.IsNull() && std::holds_alternative<Get<Pose>>(field.member)) {
    text = "none";
  } else if (!value.IsScalar()) {
    throw ConfigError(source, line, field.key + ": expected " + kind_of(field) + ", got " + node_kind(value));
  } else {
    text = value.Scalar();
  }
  if (const auto error = assign(field, config, text); !error.empty())
    throw ConfigError(source, line, field.key + ": " + error);
}

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

}  // namespace

bool operator==(const Config& a, const Config& b) {
  // The accessors hand out references for writing too, so compare copies.
  Config x = a, y = b;
  return std::all_of(table().begin(), table().end(),
                     [&](const Field& f) { return format_value(f, x) == format_value(f, y); });
}

std::vector<std::string> config_keys() {
  std::vector<std::string> keys;
  for (const auto& f : table()) keys.push_back(f.key);
  return keys;
}

Config parse_config(std::string_view yaml_text, const std::filesystem::path& source) {
  YAML::Node root;
  try {
    root = YAML::Load(std::string(yaml_text));
  } catch (const YAML::Exception& e) {
    throw ConfigError(source, line_of(e.mark), "YAML: " + e.msg);
  }
  Config config;
  if (root.IsNull()) return config;  // an empty file: all defaults
  if (!root.IsMap()) throw ConfigError(source, line_of(root.Mark()), "expected a mapping of sections (cvo: ...)");

  std::map<std::string, std::size_t> seen;  // key or section -> line, to report duplicates
  const auto first_time = [&](const std::string& key, std::size_t line) {
    if (const auto [it, fresh] = seen.emplace(key, line); !fresh)
      throw ConfigError(source, line, key + ": given twice (first on line " + std::to_string(it->second) + ")");
  };

  for (const auto& top : root) {
    const std::string name = top.first.Scalar();
    const std::size_t line = line_of(top.first.Mark());
    first_time(name, line);
    if (const Field* field = find_field(name)) {
      set_from_node(*field, top.second, line, config, source);
      continue;
    }
    if (!is_section(name))
      throw ConfigError(source, line, name + ": unknown section" + suggestion(name, top_level_names()));
    if (top.second.IsNull()) continue;  // "cvo:" with nothing under it
    if (!top.second.IsMap())
      throw ConfigError(source, line, name + ": expected a mapping of keys, e.g. '" + name + ": {key: value}'");
    for (const auto& entry : top.second) {
      const std::string key = name + "." + entry.first.Scalar();
      const std::size_t key_line = line_of(entry.first.Mark());
      const Field* field = find_field(key);
      if (!field) throw ConfigError(source, key_line, key + ": unknown key" + suggestion(key, config_keys()));
      first_time(key, key_line);
      set_from_node(*field, entry.second, key_line, config, source);
    }
  }
  check_consistency(config, source);
  return config;
}

Config load_config(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ConfigError(file, "cannot open config file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError(file, "read error");
  return parse_config(text.str(), file);
}

void apply_override(Config& config, std::string_view assignment) {
  const std::filesystem::path source = "--set";
  const auto eq = assignment.find('=');
  if (eq == std::string_view::npos)
    throw ConfigError(source, "'" + std::string(assignment) + "': expected key=value, e.g. cvo.ell_init=0.15");
  const std::string key(trim(assignment.substr(0, eq)));
  const Field* field = find_field(key);
  if (!field) {
    const bool section = is_section(key);
    throw ConfigError(source, key + (section ? ": a section; set one of its keys, e.g. " + key + ".<key>=value"
                                             : ": unknown key" + suggestion(key, config_keys())));
  }
  Config updated = config;  // config stays as it was if anything is wrong
  if (const auto error = assign(*field, updated, trim(assignment.substr(eq + 1))); !error.empty())
    throw ConfigError(source, key + ": " + error);
  check_consistency(updated, source);
  config = std::move(updated);
}

std::string dump_config(const Config& config) {
  Config c = config;                 // the accessors need a mutable object; they only read here
  std::vector<std::string> entries;  // "  key: value", before comments are aligned
  std::size_t width = 0;
  for (const auto& f : table()) {
    const auto section = section_of(f.key);
    const auto member = section.empty() ? std::string_view(f.key) : std::string_view(f.key).substr(section.size() + 1);
    entries.push_back((section.empty() ? "" : "  ") + std::string(member) + ": " + format_value(f, c));
    width = std::max(width, entries.back().size());
  }

  std::string out =
      "# cvo-slam configuration, every key with its value. A file may give any subset, and\n"
      "# '--set section.key=value' overrides one key; the rest keep their defaults, the paper's\n"
      "# Table 1 (libcvo/core/parameters.hpp). libcvo/config/default.yaml is this for the defaults.\n";
  std::string_view open_section = "-";
  for (std::size_t i = 0; i < table().size(); ++i) {
    const auto& f = table()[i];
    if (const auto section = section_of(f.key); section != open_section) {
      out.append("\n");
      if (!section.empty()) out.append(section).append(":\n");
      open_section = section;
    }
    std::string comment(f.doc);
    if (f.range.lo != -kInf || f.range.hi != kInf) comment.append("; ").append(f.range.text());
    out.append(entries[i]).append(width + 2 - entries[i].size(), ' ').append("# ").append(comment).append("\n");
  }
  return out;
}

std::string robot_name(std::string_view configured) {
  if (configured != kHostName) return std::string(configured);
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0 || !core::is_robot_name(host)) return "localhost";
  return host;
}

bool keyframes_in_chunks(const TrackerdParameters& trackerd) {
  if (trackerd.keyframe_transport != "auto") return trackerd.keyframe_transport == "chunks";
  return !trackerd.lcm_url.starts_with("file://");
}

}  // namespace cvo::config
