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
#include "libcvo/eval/nees.hpp"
#include "libcvo/eval/plot.hpp"
#include "libcvo/eval/rpe.hpp"
#include "libcvo/eval/trajectory_checks.hpp"
#include "libcvo/io/covariance_io.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "program/cli.hpp"
#include "program/json.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;

constexpr const char* kDescription =
    R"(Evaluates ESTIMATE against GROUNDTRUTH (TUM trajectory files: 'timestamp tx ty tz qx qy qz qw')
exactly as the TUM RGB-D benchmark scripts do:
  ATE  evaluate_ate.py: poses associated by timestamp (|dt| < max-dt), rigid alignment without
       scale, RMSE/mean/median/std/min/max of the position error [m];
  RPE  evaluate_rpe.py --fixed_delta --delta_unit s: errors of the relative motion over delta
       seconds, translation [m per delta] and rotation [deg per delta] (m/s, deg/s for delta 1).
  NEES with --covariance COV (cvo-run --covariance-out): of each frame-to-frame relative pose that
       has a covariance, against the ground truth interpolated at both stamps (libcvo/eval/nees.hpp);
       a consistent estimator averages 6 (3 translation, 3 rotation).
)";

struct Arguments {
  fs::path groundtruth, estimate;
  bool json = false;
  std::optional<fs::path> plot, covariance;
  double max_dt = 0.02, delta = 1.0, offset = 0.0;
};

void add_options(CLI::App& app, Arguments& args) {
  app.add_option("GROUNDTRUTH", args.groundtruth, "ground-truth TUM trajectory")->required();
  app.add_option("ESTIMATE", args.estimate, "estimated TUM trajectory")->required();
  app.add_flag("--json", args.json, "print one JSON object instead of the table");
  app.add_option("--plot", args.plot, "write a figure: top view with the aligned estimate, and the error over time")
      ->type_name("PNG");
  app.add_option("--covariance", args.covariance, "NEES of the relative poses with these covariances")
      ->type_name("COV");
  app.add_option("--max-dt", args.max_dt, "association window for ATE, seconds")->check(program::kPositive);
  app.add_option("--delta", args.delta, "RPE time step, seconds")->check(program::kPositive);
  app.add_option("--offset", args.offset, "time offset added to the estimate's timestamps, seconds");
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

void print_json(const Arguments& args, const eval::AteResult& ate, const std::optional<eval::RpeResult>& rpe,
                const std::optional<eval::NeesResult>& nees) {
  const auto rpe_value = [&](auto get) -> program::Json { return rpe ? program::Json(get(*rpe)) : program::Json(); };
  program::Json o;
  o["groundtruth"] = args.groundtruth.string();
  o["estimate"] = args.estimate.string();
  o["pairs"] = ate.pairs.size();
  o["max_dt_s"] = args.max_dt;
  o["ate_rmse_m"] = ate.error.rmse;
  o["ate_mean_m"] = ate.error.mean;
  o["ate_median_m"] = ate.error.median;
  o["ate_std_m"] = ate.error.stddev;
  o["ate_min_m"] = ate.error.min;
  o["ate_max_m"] = ate.error.max;
  o["rpe_pairs"] = rpe ? rpe->pairs.size() : 0;
  o["rpe_delta_s"] = args.delta;
  o["rpe_trans_m_s"] = rpe_value([](const auto& r) { return r.translation.rmse; });
  o["rpe_trans_mean_m_s"] = rpe_value([](const auto& r) { return r.translation.mean; });
  o["rpe_trans_median_m_s"] = rpe_value([](const auto& r) { return r.translation.median; });
  o["rpe_trans_max_m_s"] = rpe_value([](const auto& r) { return r.translation.max; });
  o["rpe_rot_deg_s"] = rpe_value([](const auto& r) { return r.rotation_deg.rmse; });
  o["rpe_rot_mean_deg_s"] = rpe_value([](const auto& r) { return r.rotation_deg.mean; });
  o["rpe_rot_median_deg_s"] = rpe_value([](const auto& r) { return r.rotation_deg.median; });
  o["rpe_rot_max_deg_s"] = rpe_value([](const auto& r) { return r.rotation_deg.max; });
  if (nees) {
    o["nees_pairs"] = nees->pairs.size();
    o["nees_mean"] = nees->nees.mean;
    o["nees_median"] = nees->nees.median;
    o["nees_translation_mean"] = nees->translation.mean;
    o["nees_rotation_mean"] = nees->rotation.mean;
  }
  std::cout << program::to_text(o);
}

void print_table(const Arguments& args, std::size_t gt_poses, std::size_t est_poses, const eval::AteResult& ate,
                 const std::optional<eval::RpeResult>& rpe, const std::optional<eval::NeesResult>& nees) {
  std::printf("ground truth  %s (%zu poses)\nestimate      %s (%zu poses)\n\n", args.groundtruth.c_str(), gt_poses,
              args.estimate.c_str(), est_poses);
  std::printf("%-20s %11s %11s %11s %11s  %s\n", "", "rmse", "mean", "median", "max", "pairs");
  const auto row = [](const std::string& name, const eval::ErrorStatistics& s, const std::string& note) {
    std::printf("%-20s %11.6f %11.6f %11.6f %11.6f  %s\n", name.c_str(), s.rmse, s.mean, s.median, s.max, note.c_str());
  };
  char note[96];
  std::snprintf(note, sizeof note, "%zu (|dt| < %g s)", ate.pairs.size(), args.max_dt);
  row("ATE [m]", ate.error, note);
  const std::string per = args.delta == 1.0 ? "/s" : " per " + program::Json(args.delta).dump() + " s";
  if (rpe) {
    std::snprintf(note, sizeof note, "%zu (delta %g s)", rpe->pairs.size(), args.delta);
    row("RPE trans [m" + per + "]", rpe->translation, note);
    row("RPE rot [deg" + per + "]", rpe->rotation_deg, "");
  } else {
    std::printf("%-20s %11s\n", "RPE", "n/a (see the warning above)");
  }
  if (nees) {
    std::snprintf(note, sizeof note, "%zu (consistent: mean 6)", nees->pairs.size());
    row("NEES", nees->nees, note);
    row("NEES translation", nees->translation, "(consistent: mean 3)");
    row("NEES rotation", nees->rotation, "(consistent: mean 3)");
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
  std::optional<eval::NeesResult> nees;
  if (args.covariance) {
    try {
      nees = eval::relative_pose_nees(gt, est, io::read_covariances(*args.covariance), {.max_difference = args.max_dt});
    } catch (const std::invalid_argument& e) {
      throw io::InputError(*args.covariance, std::string("against ") + args.estimate.string() + ": " + e.what());
    }
  }
  if (args.plot) eval::write_evaluation_plot(*args.plot, gt, est, ate, {.title = args.estimate.filename().string()});
  if (args.json)
    print_json(args, ate, rpe, nees);
  else
    print_table(args, gt.size(), est.size(), ate, rpe, nees);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  CLI::App app(kDescription, "cvo-eval");
  program::describe(app, "cvo-eval GROUNDTRUTH ESTIMATE [options]");
  add_options(app, args);
  return program::cli_main(app, argc, argv, [&] { return run(args); });
}
