// cvo-run: the offline pipeline. Streams a TUM-layout recording through an odometry mode, writes
// the estimated trajectory, and reports failures, timing and (with ground truth) ATE and RPE.
//
// A contract that scripts rely on (extras may be added, nothing here changed):
//   cvo-run SEQUENCE --out TRAJ.txt [--mode cvo] [--max-frames N] [--groundtruth GT] [--plot PNG]
//           [--json] [--config FILE] [--set key=value]... [--vocabulary FILE]
//   cvo-run --mode slam SEQUENCE [SEQUENCE ...] ...: each folder a session of one map
//   --json prints one JSON object on stdout (keys in report.cpp; the human summary then goes to
//   stderr); exit status 0 ok, 1 bad input (the message names the file), 2 usage error.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <variant>
#include <vector>

#include "frame_feed.hpp"
#include "libcvo/config/config.hpp"
#include "libcvo/config/module_parameters.hpp"
#include "libcvo/core/camera.hpp"
#include "libcvo/core/units.hpp"
#include "libcvo/eval/ate.hpp"
#include "libcvo/eval/plot.hpp"
#include "libcvo/eval/rpe.hpp"
#include "libcvo/io/accelerometer.hpp"
#include "libcvo/io/covariance_io.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/io/intrinsics_file.hpp"
#include "libcvo/io/map_files.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/odometry/frame_to_frame.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"
#include "libcvo/odometry/opencv_odometry.hpp"
#include "libcvo/slam/trajectory_correction.hpp"
#include "localize.hpp"
#include "program/cli.hpp"
#include "program/configuration.hpp"
#include "program/progress.hpp"
#include "report.hpp"
#include "slam_pipeline.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;

constexpr const char* kSynopsis =
    "cvo-run SEQUENCE --out TRAJ.txt [--mode MODE] [--max-frames N] [--groundtruth GT]\n"
    "               [--plot PNG] [--json] [--config FILE] [--set key=value]... [--vocabulary FILE]\n"
    "       cvo-run --mode slam SEQUENCE [SEQUENCE ...] --out TRAJ.txt [--store FILE] [options as above]\n"
    "       cvo-run --mode localize SEQUENCE --map-store FILE --out TRAJ.txt [options as above]";

constexpr const char* kDescription =
    R"(Runs odometry over SEQUENCE, a folder in TUM RGB-D layout (rgb.txt, depth.txt, images, optional
groundtruth.txt), or any source cvo-trackerd reads (openni2:FILE.oni, lcm:file://LOG, tum:DIR, a
device: every frame, as fast as it is tracked; --mode kf-cvo gives cvo-trackerd --deterministic's
poses), and writes the estimated poses T_world_camera as a TUM trajectory, stamped with
the colour images' timestamps. A frame whose images cannot be read is skipped and reported (it has
no pose); a frame that cannot be tracked keeps the constant-velocity prediction and is reported.

With --mode slam, several folders are several sessions of one map (a robot mapping a building in
several runs), run in order through one back end: each starts in its own odometry frame and joins
the first one's map at its first verified loop to it. TRAJ.txt holds every joined session's frames
in the first session's map frame; a session that never joined is left out and reported so (--json:
"sessions"). Ground truth: --groundtruth, else every folder's groundtruth.txt together. --store FILE
writes the keyframe store cvo-backendd would write from the same keyframes (a new file), which
cvo-backendd --store and cvo-map read.

With --mode localize, SEQUENCE is localized in the map of --map-store (a keyframe store, read only):
KF-CVO tracks it, each keyframe is verified against the map as a session joins it, and TRAJ.txt
holds the map poses of the frames tracked while localized (the correction as it stood then, times
the odometry pose: what a daemon would publish). A frame whose odometry fails starts a new session,
localized again without a hint. --json adds localized_frames, localized_after_s, relocalizations
and frames_localizing / frames_localized / frames_lost.

modes (--mode):
  cvo              frame-to-frame CVO, the paper's baseline (default)
  kf-cvo           keyframe-based CVO (paper section 4; keyframes by γ, t, θ)
  slam             CVO SLAM, kf-cvo with loop closure and the robust pose graph (paper sections
                   5-6); the trajectory written is the final global optimisation's, and the
                   report also gives kf-cvo's own ATE
  localize         kf-cvo localized in a stored map (--map-store), which it never changes
  opencv-rgbd      OpenCV contrib's dense photometric RGB-D odometry
  opencv-rgbd-icp  OpenCV's photometric + point-to-plane ICP odometry
                   (both frame to frame with the same motion model; depth 0.1-5 m, from
                   selection.min_depth_m / max_depth_m))";

constexpr const char* kNotes =
    R"(camera: --set camera=PRESET|FILE, else the config file's camera if it differs from the default,
else SEQUENCE/camera.yaml (cvo-render writes one), else the preset the folder name names
(fr1/fr2/fr3, freiburg1..3); without any of these cvo-run stops (exit 1).

vocabulary: --vocabulary, else the committed one of the source tree cvo-run was built from, else the
installed share/cvo-slam copy.)";

using program::UsageError;

struct Arguments {
  std::vector<fs::path> sequences;
  fs::path out;
  std::string mode = "cvo";
  std::size_t max_frames = 0;  // 0 = all
  std::optional<fs::path> groundtruth, plot, config, vocabulary, map, map_plot, store, map_store, covariance_out;
  std::vector<std::string> sets;
  bool json = false;
};

void add_options(CLI::App& app, Arguments& args) {
  app.add_option("SEQUENCE", args.sequences,
                 "TUM RGB-D folder, or a source (openni2:FILE.oni, lcm:URL, ...); with --mode slam, one per session")
      ->required();
  app.add_option("--out", args.out, "the trajectory to write")->required()->type_name("TRAJ.txt");
  app.add_option("--mode", args.mode, "the odometry (see modes above)")
      ->check(CLI::IsMember({"cvo", "kf-cvo", "slam", "localize", "opencv-rgbd", "opencv-rgbd-icp"}));
  app.add_option("--max-frames", args.max_frames, "only the first N frames (of each folder)")
      ->transform(program::kDecimal)
      ->check(program::kPositive)
      ->default_str("all");
  app.add_option("--groundtruth", args.groundtruth, "evaluate against this TUM trajectory")
      ->type_name("GT")
      ->default_str("SEQUENCE/groundtruth.txt");
  app.add_option("--plot", args.plot, "write the evaluation figure (needs ground truth)")->type_name("PNG");
  app.add_flag("--json", args.json, "print one JSON object on stdout; the summary then goes to stderr");
  app.add_option("--map", args.map,
                 "--mode slam: write the final map here: grid.pgm + grid.yaml (Nav2 map_server), cloud.ply, octomap.bt")
      ->type_name("DIR");
  app.add_option("--map-plot", args.map_plot, "--mode slam with --map: the grid with the keyframe trajectory on it")
      ->type_name("PNG");
  app.add_option("--store", args.store,
                 "--mode slam: write the keyframe store cvo-backendd would write (a new file; cvo-backendd --store and "
                 "cvo-map read it)")
      ->type_name("FILE");
  app.add_option("--map-store", args.map_store,
                 "--mode localize: the keyframe store of the map to localize in (read only, never changed)")
      ->type_name("FILE");
  app.add_option("--covariance-out", args.covariance_out,
                 "kf-cvo and slam: per frame its timestamp, then the 36 entries (row-major, [rho; phi], right "
                 "perturbation) of the frame-to-frame relative pose's covariance; frames without a measured motion "
                 "(the first, a restart, a failure) have no line")
      ->type_name("COV");
  app.add_option("--config", args.config, "parameters (YAML, see libcvo/config/default.yaml)")->type_name("FILE");
  program::add_set_option(app, args.sets, "cvo.ell_init=0.12");
  app.add_option("--vocabulary", args.vocabulary, "the ORB vocabulary of --mode slam and localize (default: see below)")
      ->type_name("FILE");
}

// See "camera:" in the help's notes. nullopt: TumSequence takes SEQUENCE/camera.yaml or the preset
// the folder name names, and says so clearly when there is neither.
std::optional<core::Intrinsics> choose_camera(const Arguments& args, const config::Config& config) {
  bool explicit_camera = args.config && config.camera != config::Config{}.camera;
  for (const auto& s : args.sets) explicit_camera = explicit_camera || s.starts_with("camera=");
  if (explicit_camera) return io::load_camera(config.camera);
  return std::nullopt;
}

// --vocabulary, else the default (an InputError when the file is missing or bad).
loop_closure::Vocabulary load_vocabulary(const Arguments& args) {
  return loop_closure::Vocabulary::load(args.vocabulary ? fs::path(*args.vocabulary)
                                                        : loop_closure::default_vocabulary_file());
}

// One tracker per mode; a mode is one more alternative and one more branch. The slam mode is
// tools::SlamPipeline, driven session by session in run_slam().
using Tracker = std::variant<odometry::FrameToFrameOdometry, odometry::KeyframeOdometry, odometry::OpenCvOdometry>;

Tracker make_tracker(const Arguments& args, const config::Config& config, const core::Intrinsics& camera) {
  const std::string_view mode = args.mode;
  if (mode == "cvo") {
    return odometry::FrameToFrameOdometry(camera.width, camera.height, config::frame_to_frame_parameters(config));
  }
  if (mode == "kf-cvo") {
    return odometry::KeyframeOdometry(camera.width, camera.height, config::keyframe_odometry_parameters(config));
  }
  if (mode == "opencv-rgbd" || mode == "opencv-rgbd-icp") {
    const auto variant = mode == "opencv-rgbd" ? odometry::OpenCvVariant::rgbd : odometry::OpenCvVariant::rgbd_icp;
    return odometry::OpenCvOdometry(camera, config::opencv_odometry_parameters(config, variant));
  }
  throw std::logic_error("make_tracker: no tracker for mode '" + std::string(mode) + "'");
}

std::string failure_reason(const odometry::TrackResult& r) {
  std::string reason = odometry::to_string(r.status);
  if (r.status == odometry::TrackStatus::kSelectionFailed)
    reason += std::string(": ") + registration::to_string(r.selection_status);
  if (r.status == odometry::TrackStatus::kRegistrationFailed)
    reason += std::string(": ") + registration::to_string(r.registration_status) + " after " +
              std::to_string(r.iterations) + " iterations";
  return reason + "; pose predicted (constant velocity)";
}

// Every folder or source opened before the (long) run, so a bad one fails at once.
std::vector<tools::FrameFeed> open_sequences(const Arguments& args, const config::Config& config) {
  std::vector<tools::FrameFeed> sequences;
  for (const auto& sequence : args.sequences) {
    io::TumOptions options = config::tum_options(config);
    options.intrinsics = choose_camera(args, config);
    options.max_frames = args.max_frames;
    sequences.push_back(tools::FrameFeed::open(sequence.string(), options));
    if (const auto what = sequences.back().describe(); !what.empty()) std::cerr << "cvo-run: reading " << what << "\n";
  }
  return sequences;
}

// --groundtruth, else every folder's ground truth together (sorted, each stamp once).
core::Trajectory load_groundtruth(const Arguments& args, const std::vector<tools::FrameFeed>& sequences,
                                  std::string& source) {
  if (args.groundtruth) {
    source = args.groundtruth->string();
    return io::read_tum_trajectory(*args.groundtruth);
  }
  core::Trajectory all;
  for (std::size_t k = 0; k < sequences.size(); ++k) {
    const auto& gt = sequences[k].groundtruth();
    if (!gt.empty()) source.append(source.empty() ? "" : " ").append((args.sequences[k] / "groundtruth.txt").string());
    all.insert(all.end(), gt.begin(), gt.end());
  }
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.timestamp < b.timestamp; });
  all.erase(
      std::unique(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.timestamp == b.timestamp; }),
      all.end());
  return all;
}

// --covariance-out: the frame's relative covariance, when it has one.
void record_covariance(const core::RgbdFrame& frame, const odometry::TrackStep& step,
                       std::vector<io::StampedCovariance>& covariances) {
  if (step.relative_covariance) covariances.push_back({frame.timestamp, *step.relative_covariance});
}

// Streams one folder through `track` (frame -> TrackResult), adding its frames to the report;
// returns the poses of the frames tracked. `keyframes` counts this folder's keyframes.
template <class Track>
core::Trajectory stream(tools::FrameFeed& sequence, Track&& track, tools::RunReport& report, std::size_t& keyframes) {
  using Clock = core::SteadyClock;
  core::Trajectory trajectory;
  trajectory.reserve(sequence.expected_frames());
  program::ProgressBar progress(sequence.expected_frames());
  const auto run_start = Clock::now();
  for (std::size_t frames = 0;;) {
    auto item = sequence.next();
    const std::size_t index = item.index;
    if (item.kind == tools::FrameFeed::Item::Kind::kBad) {
      // The sequence has moved past the frame: report it and go on with the next one.
      report.failed.push_back({item.index, item.timestamp, "read", item.error});
      progress.update(++frames);
      ++report.frames;
      continue;
    }
    if (item.kind == tools::FrameFeed::Item::Kind::kEnd) {
      if (!item.error.empty()) std::cerr << "cvo-run: the source ended: " << item.error << "\n";
      break;
    }
    std::optional<core::RgbdFrame>& frame = item.frame;
    const auto start = Clock::now();
    const odometry::TrackResult r = track(*frame);
    report.track_ms.push_back(core::ms_since(start));
    trajectory.push_back({frame->timestamp, r.published_pose()});
    report.points.push_back(static_cast<double>(r.points));
    if (r.iterations > 0) report.iterations.push_back(r.iterations);
    if (r.keyframe) ++keyframes;
    if (!r.tracked())
      report.failed.push_back({index, frame->timestamp,
                               r.status == odometry::TrackStatus::kSelectionFailed ? "selection" : "registration",
                               failure_reason(r)});
    progress.update(++frames);
    ++report.frames;
  }
  report.wall_s += std::chrono::duration<double>(Clock::now() - run_start).count();
  return trajectory;
}

// --map DIR (and --map-plot PNG): the final map's files; the plot's trajectory is the keyframes of
// the sessions in the map.
tools::MapReport write_map(const Arguments& args, const mapping::Mapping& mapping, const slam::Map& map,
                           double place_ms) {
  io::write_map_files(*args.map, mapping);
  const auto grid = mapping.grid();  // write_map_files throws without one
  const auto keyframes = mapping::placed_keyframes(map);
  if (args.map_plot) {
    std::vector<Eigen::Vector3d> centres;
    for (const auto* k : keyframes) centres.push_back(k->pose.translation());
    io::write_map_plot(*args.map_plot, *grid, centres);
  }
  const auto statistics = mapping.statistics();
  tools::MapReport m;
  m.dir = args.map->string();
  m.up = mapping::up_source_name(grid->frame.up);
  m.width = grid->grid.width, m.height = grid->grid.height, m.resolution = grid->grid.resolution;
  for (const auto c : grid->grid.cells) m.occupied += c == 100, m.free += c == 0;
  m.keyframes = statistics.placed;
  m.bytes_per_keyframe =
      statistics.keyframes ? static_cast<double>(statistics.local_map_bytes) / statistics.keyframes : 0;
  m.cloud_points = mapping.cloud().size();
  m.place_ms = place_ms;
  for (const auto* k : keyframes) m.keyframe_timestamps.push_back(k->timestamp);
  return m;
}

// --mode slam: every folder a session (ids 1, 2, ... in order) of one mapper; the trajectory is
// every joined session's frames in the map frame, kf-cvo's own poses corrected by the back end
// (slam::correct_trajectory fills in the frames it never saw).
core::Trajectory run_slam(const Arguments& args, const config::Config& config, std::vector<tools::FrameFeed>& sequences,
                          const core::Trajectory& groundtruth, tools::RunReport& report,
                          std::vector<io::StampedCovariance>& covariances) {
  tools::SlamPipeline pipeline(config, load_vocabulary(args), args.map.has_value(), args.store);
  std::vector<core::Trajectory> odometry(sequences.size());
  report.slam = tools::SlamReport{};
  for (std::size_t k = 0; k < sequences.size(); ++k) {
    const auto session = static_cast<core::SessionId>(k + 1);
    const auto& camera = sequences[k].intrinsics();
    const fs::path accelerometer = args.sequences[k] / "accelerometer.txt";
    pipeline.begin_session(session, camera.width, camera.height,
                           args.map && fs::exists(accelerometer) ? io::read_tum_accelerometer(accelerometer)
                                                                 : std::vector<io::AccelerometerSample>{});
    tools::SessionEntry entry{args.sequences[k].string(), session, report.frames, 0, false, std::nullopt};
    odometry[k] = stream(
        sequences[k],
        [&](const core::RgbdFrame& f) -> odometry::TrackResult {
          const odometry::TrackStep step = pipeline.track(f);
          record_covariance(f, step, covariances);
          return step;
        },
        report, entry.keyframes);
    entry.frames = report.frames - entry.frames;
    report.keyframes += entry.keyframes;
    report.slam->sessions.push_back(entry);
  }
  pipeline.finish();

  const slam::Mapper& mapper = pipeline.mapper();
  const slam::Map map = mapper.map();
  core::Trajectory trajectory;
  for (std::size_t k = 0; k < sequences.size(); ++k) {
    auto& entry = report.slam->sessions[k];
    entry.joined = mapper.placed(entry.session);
    for (const auto& s : map.sessions)
      if (s.session == entry.session && s.joined_at_keyframe >= 0) entry.joined_at_keyframe = s.joined_at_keyframe;
    if (!entry.joined || odometry[k].empty()) continue;
    const auto corrected = slam::correct_trajectory(odometry[k], mapper.frame_trajectory(entry.session));
    trajectory.insert(trajectory.end(), corrected.begin(), corrected.end());
  }
  auto& s = *report.slam;
  s.loops_accepted = mapper.loops_accepted();
  s.loops_tried = mapper.loops_tried();
  s.keyframes_merged = mapper.merged_keyframes();
  s.graph_nodes = mapper.backend().keyframe_graph().nodes().size();
  s.graph_edges = mapper.backend().keyframe_graph().edges().size();
  s.backend_ms = pipeline.statistics().backend_ms;
  s.final_optimisation_ms = pipeline.statistics().final_ms;
  for (const auto& l : map.loops)
    s.loops.push_back({l.from_frame, l.to_frame, l.chi2, l.weight, l.from_session, l.to_session});
  if (args.map) s.map = write_map(args, *pipeline.mapping(), map, pipeline.statistics().map_ms);
  if (const auto* store = pipeline.store())
    s.store = tools::StoreReport{args.store->string(), store->records(), pipeline.statistics().store_ms};
  // kf-cvo's own ATE: one session only (several have several odometry frames).
  if (!groundtruth.empty() && sequences.size() == 1 && !odometry[0].empty()) {
    try {
      s.ate_odometry = eval::absolute_trajectory_error(groundtruth, odometry[0]);
    } catch (const std::invalid_argument&) {
      // As for the main ATE, which says why.
    }
  }
  return trajectory;
}

// --mode localize: one folder, one session after another in the stored map (localize.hpp).
core::Trajectory run_localize(const Arguments& args, const config::Config& config, tools::FrameFeed& sequence,
                              tools::RunReport& report) {
  tools::Localizer localizer(config, load_vocabulary(args), *args.map_store, std::cerr);
  stream(
      sequence, [&](const core::RgbdFrame& f) { return localizer.track(f); }, report, report.keyframes);
  report.localize = localizer.report();
  report.localize->map_store = args.map_store->string();
  return localizer.trajectory();
}

void evaluate(const Arguments& args, const core::Trajectory& groundtruth, const core::Trajectory& trajectory,
              tools::RunReport& report) {
  // A short run may have an ATE but no 1 s RPE pairs: report what exists instead of failing.
  try {
    report.ate = eval::absolute_trajectory_error(groundtruth, trajectory);
  } catch (const std::invalid_argument& e) {
    std::cerr << "cvo-run: warning: no ATE: " << e.what() << "\n";
  }
  try {
    report.rpe = eval::relative_pose_error(groundtruth, trajectory);
  } catch (const std::invalid_argument& e) {
    std::cerr << "cvo-run: warning: no RPE: " << e.what() << "\n";
  }
  if (!args.plot) return;
  if (report.ate)
    eval::write_evaluation_plot(*args.plot, groundtruth, trajectory, *report.ate,
                                {.title = args.out.filename().string() + " (" + args.mode + ")"});
  else
    std::cerr << "cvo-run: warning: no plot written: no ATE\n";
}

int run(const Arguments& args) {
  if (args.sequences.size() > 1 && args.mode != "slam")
    throw UsageError("several SEQUENCE folders (sessions) need --mode slam; got " +
                     std::to_string(args.sequences.size()) + " for mode '" + args.mode + "'");
  const config::Config config = program::configuration(args.config, args.sets);
  std::vector<tools::FrameFeed> sequences = open_sequences(args, config);

  // Everything that can fail on input is checked before the (long) run.
  tools::RunReport report;
  const core::Trajectory groundtruth = load_groundtruth(args, sequences, report.groundtruth);
  if ((args.map || args.map_plot) && args.mode != "slam")
    throw UsageError("--map and --map-plot need --mode slam (the map is made from the SLAM map's keyframes)");
  if (args.map_plot && !args.map) throw UsageError("--map-plot needs --map DIR");
  if (args.store && args.mode != "slam") throw UsageError("--store needs --mode slam (it stores the SLAM keyframes)");
  if ((args.mode == "localize") != args.map_store.has_value())
    throw UsageError(args.map_store ? "--map-store needs --mode localize" : "--mode localize needs --map-store FILE");
  if (args.covariance_out && args.mode != "kf-cvo" && args.mode != "slam")
    throw UsageError("--covariance-out needs --mode kf-cvo or slam (mode '" + args.mode + "' has no covariance)");
  if (args.covariance_out && !std::ofstream(*args.covariance_out))
    throw io::InputError(*args.covariance_out, "cannot write the covariances here");
  if (args.plot && groundtruth.empty())
    throw UsageError("--plot needs ground truth: " + args.sequences.front().string() +
                     " has no groundtruth.txt and no --groundtruth was given");
  if (!std::ofstream(args.out)) throw io::InputError(args.out, "cannot write the trajectory here");
  report.mode = args.mode;
  // append(), not operator+ of short strings: GCC 12 warns falsely (-Wrestrict) on that.
  for (const auto& folder : args.sequences)
    report.sequence.append(report.sequence.empty() ? "" : " ").append(folder.string());
  report.trajectory = args.out.string();

  core::Trajectory trajectory;
  std::vector<io::StampedCovariance> covariances;
  if (args.mode == "slam") {
    trajectory = run_slam(args, config, sequences, groundtruth, report, covariances);
  } else if (args.mode == "localize") {
    trajectory = run_localize(args, config, sequences.front(), report);
  } else {
    Tracker tracker = make_tracker(args, config, sequences.front().intrinsics());
    trajectory = stream(
        sequences.front(),
        [&](const core::RgbdFrame& f) {
          return std::visit(
              [&](auto& t) -> odometry::TrackResult {
                auto step = t.track(f);
                if constexpr (std::is_same_v<decltype(step), odometry::TrackStep>)
                  record_covariance(f, step, covariances);
                return step;
              },
              tracker);
        },
        report, report.keyframes);
  }
  // SLAM and localization may leave frames out (unplaced sessions, frames not localized).
  const bool may_leave_out = report.slam || report.localize;
  if (trajectory.empty() && (!may_leave_out || report.frames == report.failed.size())) {
    io::write_tum_trajectory(args.out, trajectory);
    throw io::InputError(args.sequences.front(), "no frame could be read");
  }
  report.poses = trajectory.size();
  io::write_tum_trajectory(args.out, trajectory);
  if (args.covariance_out) io::write_covariances(*args.covariance_out, covariances);
  if (!groundtruth.empty() && !trajectory.empty()) evaluate(args, groundtruth, trajectory, report);

  tools::print_text(args.json ? stderr : stdout, report);
  if (args.json) std::cout << program::to_text(tools::to_json(report)) << std::flush;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  CLI::App app(kDescription, "cvo-run");
  program::describe(app, kSynopsis, kNotes);
  add_options(app, args);
  return program::cli_main(app, argc, argv, [&] { return run(args); });
}
