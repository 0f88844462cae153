// cvo-run: the offline pipeline. Streams a TUM-layout recording through an odometry mode, writes
// the estimated trajectory, and reports failures, timing and (with ground truth) ATE and RPE.
//
// A contract that scripts rely on (extras may be added, nothing here changed):
//   cvo-run SEQUENCE --out TRAJ.txt [--mode cvo] [--max-frames N] [--groundtruth GT] [--plot PNG]
//           [--json] [--config FILE] [--set key=value]... [--vocabulary FILE]
//   --json prints one JSON object on stdout (keys in report.cpp; the human summary then goes to
//   stderr); exit status 0 ok, 1 bad input (the message names the file), 2 usage error.
#include <unistd.h>

#include <charconv>
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <variant>
#include <vector>

#include "libcvo/config/config.hpp"
#include "libcvo/core/camera.hpp"
#include "libcvo/eval/ate.hpp"
#include "libcvo/eval/plot.hpp"
#include "libcvo/eval/rpe.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/io/intrinsics_file.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/odometry/frame_to_frame.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"
#include "libcvo/odometry/opencv_odometry.hpp"
#include "libcvo/slam/trajectory_correction.hpp"
#include "progress.hpp"
#include "report.hpp"
#include "slam_pipeline.hpp"
#include "tools/common/cli.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;

constexpr std::string_view kUsage =
    R"(usage: cvo-run SEQUENCE --out TRAJ.txt [--mode MODE] [--max-frames N] [--groundtruth GT]
               [--plot PNG] [--json] [--config FILE] [--set key=value]... [--vocabulary FILE]

Runs odometry over SEQUENCE, a folder in TUM RGB-D layout (rgb.txt, depth.txt, images, optional
groundtruth.txt), and writes the estimated poses T_world_camera as a TUM trajectory, stamped with
the colour images' timestamps. A frame whose images cannot be read is skipped and reported (it has
no pose); a frame that cannot be tracked keeps the constant-velocity prediction and is reported.

options:
  --out TRAJ.txt     the trajectory to write (required)
  --mode MODE        cvo: frame-to-frame CVO, the paper's baseline (default)
                     kf-cvo: keyframe-based CVO (paper section 4; keyframes by γ, t, θ)
                     slam: CVO SLAM, kf-cvo with loop closure and the robust pose graph
                     (paper sections 5-6); the trajectory written is the final global
                     optimisation's, and the report also gives kf-cvo's own ATE
                     opencv-rgbd: OpenCV contrib's dense photometric RGB-D odometry
                     opencv-rgbd-icp: OpenCV's photometric + point-to-plane ICP odometry
                     (both frame to frame with the same motion model; depth 0.1-5 m, from
                     selection.min_depth_m / max_depth_m)
  --max-frames N     only the first N frames
  --groundtruth GT   evaluate against this TUM trajectory (default: SEQUENCE/groundtruth.txt)
  --plot PNG         write the evaluation figure (needs ground truth)
  --json             print one JSON object on stdout; the summary then goes to stderr
  --config FILE      parameters (YAML, see libcvo/config/default.yaml)
  --set KEY=VALUE    override one parameter, e.g. --set cvo.ell_init=0.12 (repeatable)
  --vocabulary FILE  the ORB vocabulary of --mode slam (default: the committed one of the
                     source tree it was built from, else the installed share/cvo-slam copy)
  --help             this text

camera: --set camera=PRESET|FILE, else the config file's camera if it differs from the default,
else SEQUENCE/camera.yaml (cvo-render writes one), else the preset the folder name names
(fr1/fr2/fr3, freiburg1..3); without any of these cvo-run stops (exit 1).

exit status: 0 ok, 1 bad input, 2 usage error
)";

using tools::UsageError;

// Every mode the contract names. Implementing one is a row flipped here and a branch in
// make_tracker().
struct ModeInfo {
  std::string_view name;
  bool implemented;
};
constexpr ModeInfo kModes[] = {
    {"cvo", true}, {"kf-cvo", true}, {"slam", true}, {"opencv-rgbd", true}, {"opencv-rgbd-icp", true}};

struct Arguments {
  fs::path sequence, out;
  std::string mode = "cvo";
  std::size_t max_frames = 0;  // 0 = all
  std::optional<fs::path> groundtruth, plot, config, vocabulary;
  std::vector<std::string> sets;
  bool json = false;
  bool help = false;
};

Arguments parse_arguments(int argc, char** argv) {
  Arguments args;
  std::vector<std::string> positional;
  for (int k = 1; k < argc; ++k) {
    const std::string_view arg = argv[k];
    const auto value = [&]() -> std::string_view {
      if (k + 1 >= argc) throw UsageError(std::string(arg) + " needs a value");
      return argv[++k];
    };
    if (arg == "--help" || arg == "-h") {
      args.help = true;
    } else if (arg == "--json") {
      args.json = true;
    } else if (arg == "--out") {
      args.out = fs::path(value());
    } else if (arg == "--mode") {
      args.mode = value();
    } else if (arg == "--max-frames") {
      const std::string_view text = value();
      std::size_t n = 0;
      const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
      if (ec != std::errc() || end != text.data() + text.size() || n == 0)
        throw UsageError("--max-frames needs a positive whole number, not '" + std::string(text) + "'");
      args.max_frames = n;
    } else if (arg == "--groundtruth") {
      args.groundtruth = fs::path(value());
    } else if (arg == "--plot") {
      args.plot = fs::path(value());
    } else if (arg == "--config") {
      args.config = fs::path(value());
    } else if (arg == "--set") {
      args.sets.emplace_back(value());
    } else if (arg == "--vocabulary") {
      args.vocabulary = fs::path(value());
    } else if (arg.size() > 1 && arg.front() == '-') {
      throw UsageError("unknown option '" + std::string(arg) + "'");
    } else {
      positional.emplace_back(arg);
    }
  }
  if (args.help) return args;
  if (positional.size() != 1)
    throw UsageError("expected one SEQUENCE folder, got " + std::to_string(positional.size()));
  args.sequence = positional[0];
  if (args.out.empty()) throw UsageError("--out TRAJ.txt is required");

  const ModeInfo* mode = nullptr;
  for (const auto& m : kModes)
    if (m.name == args.mode) mode = &m;
  if (mode == nullptr)
    throw UsageError("unknown mode '" + args.mode + "' (cvo, kf-cvo, slam, opencv-rgbd or opencv-rgbd-icp)");
  if (!mode->implemented) {
    std::string implemented;
    for (const auto& m : kModes)
      if (m.implemented) implemented.append(implemented.empty() ? "" : ", ").append(m.name);
    throw UsageError("mode '" + args.mode + "' is not implemented yet; these are: " + implemented);
  }
  return args;
}

// The config file (an InputError, exit 1, when bad), then the --set overrides (a usage error).
config::Config make_config(const Arguments& args) {
  config::Config config = args.config ? config::load_config(*args.config) : config::Config{};
  for (const auto& assignment : args.sets) {
    try {
      config::apply_override(config, assignment);
    } catch (const config::ConfigError& e) {
      throw UsageError(e.what());
    }
  }
  return config;
}

// See "camera:" in the usage text. nullopt: TumSequence takes SEQUENCE/camera.yaml or the preset
// the folder name names, and says so clearly when there is neither.
std::optional<core::Intrinsics> choose_camera(const Arguments& args, const config::Config& config) {
  bool explicit_camera = args.config && config.camera != config::Config{}.camera;
  for (const auto& s : args.sets) explicit_camera = explicit_camera || s.starts_with("camera=");
  if (explicit_camera) return io::load_camera(config.camera);
  return std::nullopt;
}

// --vocabulary, else the default (an InputError when the file is missing or bad).
loop_closure::Vocabulary load_vocabulary(const Arguments& args) {
  return loop_closure::Vocabulary::load(args.vocabulary ? fs::path(*args.vocabulary) : loop_closure::default_vocabulary_file());
}

// One tracker per mode; a mode is one more alternative and one more branch.
using Tracker = std::variant<odometry::FrameToFrameOdometry, odometry::KeyframeOdometry, odometry::OpenCvOdometry,
                             tools::SlamPipeline>;

Tracker make_tracker(const Arguments& args, const config::Config& config, const core::Intrinsics& camera) {
  const std::string_view mode = args.mode;
  if (mode == "cvo") {
    odometry::FrameToFrameParameters parameters;
    parameters.selection = config.selection;
    parameters.cvo = config.cvo;
    return odometry::FrameToFrameOdometry(camera.width, camera.height, parameters);
  }
  if (mode == "kf-cvo") {
    odometry::KeyframeOdometryParameters parameters;
    parameters.selection = config.selection;
    parameters.cvo = config.cvo;
    parameters.keyframe = config.keyframe;
    return odometry::KeyframeOdometry(camera.width, camera.height, parameters);
  }
  if (mode == "slam")
    return Tracker(std::in_place_type<tools::SlamPipeline>, camera.width, camera.height, config, load_vocabulary(args));
  if (mode == "opencv-rgbd" || mode == "opencv-rgbd-icp") {
    odometry::OpenCvOdometryParameters parameters;
    parameters.variant = mode == "opencv-rgbd" ? odometry::OpenCvVariant::rgbd : odometry::OpenCvVariant::rgbd_icp;
    parameters.min_depth_m = config.selection.min_depth_m;
    parameters.max_depth_m = config.selection.max_depth_m;
    return odometry::OpenCvOdometry(camera, parameters);
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

int run(const Arguments& args) {
  const config::Config config = make_config(args);
  if (!fs::is_directory(args.sequence)) throw io::InputError(args.sequence, "no such folder");
  io::TumOptions options{.max_association_dt = config.dataset.max_association_dt,
                         .intrinsics = choose_camera(args, config),
                         .max_frames = args.max_frames};
  io::TumSequence sequence = io::TumSequence::open(args.sequence, options);

  // Everything that can fail on input is checked before the (long) run.
  const core::Trajectory groundtruth =
      args.groundtruth ? io::read_tum_trajectory(*args.groundtruth) : sequence.groundtruth();
  if (args.plot && groundtruth.empty())
    throw UsageError("--plot needs ground truth: " + args.sequence.string() +
                     " has no groundtruth.txt and no --groundtruth was given");
  if (!std::ofstream(args.out)) throw io::InputError(args.out, "cannot write the trajectory here");

  tools::RunReport report;
  report.mode = args.mode;
  report.sequence = args.sequence.string();
  report.trajectory = args.out.string();
  if (!groundtruth.empty())
    report.groundtruth = args.groundtruth ? args.groundtruth->string() : (args.sequence / "groundtruth.txt").string();

  Tracker tracker = make_tracker(args, config, sequence.intrinsics());
  core::Trajectory trajectory;
  trajectory.reserve(sequence.size());
  {
    tools::ProgressBar progress(sequence.size());
    using Clock = std::chrono::steady_clock;
    const auto run_start = Clock::now();
    for (;;) {
      const std::size_t index = sequence.position();
      std::optional<core::RgbdFrame> frame;
      try {
        frame = sequence.next();
      } catch (const io::FrameError& e) {
        // The sequence has moved past the frame: report it and go on with the next one.
        report.failed.push_back({e.frame_index(), sequence.files()[index].timestamp, "read", e.what()});
        progress.update(++report.frames);
        continue;
      }
      if (!frame) break;
      const auto start = Clock::now();
      const odometry::TrackResult r = std::visit([&](auto& t) { return t.track(*frame); }, tracker);
      report.track_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
      trajectory.push_back({frame->timestamp, r.pose});
      report.points.push_back(static_cast<double>(r.points));
      if (r.iterations > 0) report.iterations.push_back(r.iterations);
      if (r.keyframe) ++report.keyframes;
      if (!r.tracked())
        report.failed.push_back({index, frame->timestamp,
                                 r.status == odometry::TrackStatus::kSelectionFailed ? "selection" : "registration",
                                 failure_reason(r)});
      progress.update(++report.frames);
    }
    report.wall_s = std::chrono::duration<double>(Clock::now() - run_start).count();
  }
  if (trajectory.empty()) {
    io::write_tum_trajectory(args.out, trajectory);
    throw io::InputError(args.sequence, "no frame could be read");
  }
  if (auto* slam = std::get_if<tools::SlamPipeline>(&tracker)) {
    // The trajectory written and evaluated is the back end's; kf-cvo's own is evaluated beside it.
    const core::Trajectory odometry = std::move(trajectory);
    trajectory = slam::correct_trajectory(odometry, slam->finish());
    const auto& s = slam->statistics();
    report.slam = tools::SlamReport{s.loops_accepted, s.loops_tried, s.backend_ms, s.final_ms, std::nullopt, {}};
    for (const auto& l : slam->backend().loops())
      report.slam->loops.push_back({l.loop.from, l.loop.to, l.chi2, l.weight});
    if (!groundtruth.empty()) {
      try {
        report.slam->ate_odometry = eval::absolute_trajectory_error(groundtruth, odometry);
      } catch (const std::invalid_argument&) {
        // As for the main ATE below, which says why.
      }
    }
  }
  report.poses = trajectory.size();
  io::write_tum_trajectory(args.out, trajectory);

  if (!groundtruth.empty()) {
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
    if (args.plot) {
      if (report.ate)
        eval::write_evaluation_plot(*args.plot, groundtruth, trajectory, *report.ate,
                                    {.title = args.out.filename().string() + " (" + args.mode + ")"});
      else
        std::cerr << "cvo-run: warning: no plot written: no ATE\n";
    }
  }

  tools::print_text(args.json ? stderr : stdout, report);
  if (args.json) std::cout << tools::to_json(report) << std::flush;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return tools::cli_main("cvo-run", kUsage, argc, argv, parse_arguments, run);
}
