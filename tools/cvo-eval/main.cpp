// cvo-eval: ATE and RPE of an estimated trajectory against ground truth, computed as the TUM RGB-D
// benchmark's evaluate_ate.py and evaluate_rpe.py (--fixed_delta --delta 1 --delta_unit s) do.
//
// A contract that scripts rely on: the positional arguments, --json and its keys, --plot, and the
// exit codes 0 (ok), 1 (bad input; the message names the file) and 2 (usage error).
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "libcvo/core/trajectory.hpp"
#include "libcvo/eval/ate.hpp"
#include "libcvo/eval/plot.hpp"
#include "libcvo/eval/rpe.hpp"
#include "libcvo/eval/trajectory_checks.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/io/json_writer.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "tools/common/cli.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;

constexpr std::string_view kUsage =
    R"(usage: cvo-eval GROUNDTRUTH ESTIMATE [--json] [--plot PNG] [--max-dt S] [--delta S] [--offset S]

Evaluates ESTIMATE against GROUNDTRUTH (TUM trajectory files: 'timestamp tx ty tz qx qy qz qw')
exactly as the TUM RGB-D benchmark scripts do:
  ATE  evaluate_ate.py: poses associated by timestamp (|dt| < max-dt), rigid alignment without
       scale, RMSE/mean/median/std/min/max of the position error [m];
  RPE  evaluate_rpe.py --fixed_delta --delta_unit s: errors of the relative motion over delta
       seconds, translation [m per delta] and rotation [deg per delta] (m/s, deg/s for delta 1).

options:
  --json        print one JSON object instead of the table
  --plot PNG    write a figure: top view with the aligned estimate, and the error over time
  --max-dt S    association window for ATE, seconds (default 0.02)
  --delta S     RPE time step, seconds (default 1)
  --offset S    time offset added to the estimate's timestamps (default 0)
  --help        this text

exit status: 0 ok, 1 bad input, 2 usage error
)";

using tools::UsageError;

struct Arguments {
  fs::path groundtruth, estimate;
  bool json = false;
  bool help = false;
  std::optional<fs::path> plot;
  double max_dt = 0.02, delta = 1.0, offset = 0.0;
};

double parse_seconds(std::string_view option, std::string_view text, bool must_be_positive) {
  double v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v) || (must_be_positive && v <= 0))
    throw UsageError(std::string(option) + " needs a " + (must_be_positive ? "positive " : "") +
                     "number of seconds, not '" + std::string(text) + "'");
  return v;
}

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
    } else if (arg == "--plot") {
      args.plot = fs::path(value());
    } else if (arg == "--max-dt") {
      args.max_dt = parse_seconds(arg, value(), true);
    } else if (arg == "--delta") {
      args.delta = parse_seconds(arg, value(), true);
    } else if (arg == "--offset") {
      args.offset = parse_seconds(arg, value(), false);
    } else if (arg.size() > 1 && arg.front() == '-') {
      throw UsageError("unknown option '" + std::string(arg) + "'");
    } else {
      positional.emplace_back(arg);
    }
  }
  if (args.help) return args;
  if (positional.size() != 2)
    throw UsageError("expected GROUNDTRUTH and ESTIMATE, got " + std::to_string(positional.size()) + " file names");
  args.groundtruth = positional[0];
  args.estimate = positional[1];
  return args;
}

// A TUM text trajectory, checked for repeated stamps here so that the message names the file.
core::Trajectory load_tum(const fs::path& file) {
  auto trajectory = io::read_tum_trajectory(file);
  if (trajectory.empty()) throw io::InputError(file, "no poses in the file");
  try {
    return eval::sorted_unique(trajectory, "the file");
  } catch (const std::invalid_argument& e) {
    throw io::InputError(file, e.what());
  }
}

// The estimate is a TUM text trajectory for now. An LCM log of CVO_POSE messages will be one more
// branch here (told apart by the log's magic number); nothing after loading needs to change.
core::Trajectory load_estimate(const fs::path& file) { return load_tum(file); }

using io::json_number;
using io::json_string;

void print_json(const Arguments& args, const eval::AteResult& ate, const std::optional<eval::RpeResult>& rpe) {
  const auto rpe_value = [&](auto get) -> std::optional<double> {
    if (!rpe) return std::nullopt;
    return get(*rpe);
  };
  std::ostringstream o;
  o << "{\n"
    << "  \"groundtruth\": " << json_string(args.groundtruth.string()) << ",\n"
    << "  \"estimate\": " << json_string(args.estimate.string()) << ",\n"
    << "  \"pairs\": " << ate.pairs.size() << ",\n"
    << "  \"max_dt_s\": " << json_number(args.max_dt) << ",\n"
    << "  \"ate_rmse_m\": " << json_number(ate.error.rmse) << ",\n"
    << "  \"ate_mean_m\": " << json_number(ate.error.mean) << ",\n"
    << "  \"ate_median_m\": " << json_number(ate.error.median) << ",\n"
    << "  \"ate_std_m\": " << json_number(ate.error.stddev) << ",\n"
    << "  \"ate_min_m\": " << json_number(ate.error.min) << ",\n"
    << "  \"ate_max_m\": " << json_number(ate.error.max) << ",\n"
    << "  \"rpe_pairs\": " << (rpe ? rpe->pairs.size() : 0) << ",\n"
    << "  \"rpe_delta_s\": " << json_number(args.delta) << ",\n"
    << "  \"rpe_trans_m_s\": " << json_number(rpe_value([](const auto& r) { return r.translation.rmse; })) << ",\n"
    << "  \"rpe_trans_mean_m_s\": " << json_number(rpe_value([](const auto& r) { return r.translation.mean; }))
    << ",\n"
    << "  \"rpe_trans_median_m_s\": " << json_number(rpe_value([](const auto& r) { return r.translation.median; }))
    << ",\n"
    << "  \"rpe_trans_max_m_s\": " << json_number(rpe_value([](const auto& r) { return r.translation.max; })) << ",\n"
    << "  \"rpe_rot_deg_s\": " << json_number(rpe_value([](const auto& r) { return r.rotation_deg.rmse; })) << ",\n"
    << "  \"rpe_rot_mean_deg_s\": " << json_number(rpe_value([](const auto& r) { return r.rotation_deg.mean; }))
    << ",\n"
    << "  \"rpe_rot_median_deg_s\": " << json_number(rpe_value([](const auto& r) { return r.rotation_deg.median; }))
    << ",\n"
    << "  \"rpe_rot_max_deg_s\": " << json_number(rpe_value([](const auto& r) { return r.rotation_deg.max; }))
    << "\n}\n";
  std::cout << o.str();
}

void print_table(const Arguments& args, std::size_t gt_poses, std::size_t est_poses, const eval::AteResult& ate,
                 const std::optional<eval::RpeResult>& rpe) {
  std::printf("ground truth  %s (%zu poses)\nestimate      %s (%zu poses)\n\n", args.groundtruth.c_str(), gt_poses,
              args.estimate.c_str(), est_poses);
  std::printf("%-20s %11s %11s %11s %11s  %s\n", "", "rmse", "mean", "median", "max", "pairs");
  const auto row = [](const std::string& name, const eval::ErrorStatistics& s, const std::string& note) {
    std::printf("%-20s %11.6f %11.6f %11.6f %11.6f  %s\n", name.c_str(), s.rmse, s.mean, s.median, s.max,
                note.c_str());
  };
  char note[96];
  std::snprintf(note, sizeof note, "%zu (|dt| < %g s)", ate.pairs.size(), args.max_dt);
  row("ATE [m]", ate.error, note);
  const std::string per = args.delta == 1.0 ? "/s" : " per " + json_number(args.delta) + " s";
  if (rpe) {
    std::snprintf(note, sizeof note, "%zu (delta %g s)", rpe->pairs.size(), args.delta);
    row("RPE trans [m" + per + "]", rpe->translation, note);
    row("RPE rot [deg" + per + "]", rpe->rotation_deg, "");
  } else {
    std::printf("%-20s %11s\n", "RPE", "n/a (see the warning above)");
  }
}

int run(const Arguments& args) {
  const core::Trajectory gt = load_tum(args.groundtruth);
  const core::Trajectory est = load_estimate(args.estimate);
  eval::AteResult ate;
  try {
    ate = eval::absolute_trajectory_error(gt, est, {.max_difference = args.max_dt, .offset = args.offset});
  } catch (const std::invalid_argument& e) {
    throw io::InputError(args.estimate, std::string("against ") + args.groundtruth.string() + ": " + e.what());
  }
  // A run shorter than delta still has an ATE: report RPE as missing rather than failing.
  std::optional<eval::RpeResult> rpe;
  try {
    rpe = eval::relative_pose_error(gt, est, {.delta = args.delta, .offset = args.offset});
  } catch (const std::invalid_argument& e) {
    std::cerr << "cvo-eval: warning: " << args.estimate.string() << ": no RPE: " << e.what() << "\n";
  }
  if (args.plot)
    eval::write_evaluation_plot(*args.plot, gt, est, ate, {.title = args.estimate.filename().string()});
  if (args.json)
    print_json(args, ate, rpe);
  else
    print_table(args, gt.size(), est.size(), ate, rpe);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return tools::cli_main("cvo-eval", kUsage, argc, argv, parse_arguments, run);
}
