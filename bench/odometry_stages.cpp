// Where KF-CVO's time per frame goes, stage by stage, over a real sequence: point selection, the
// frame-to-frame registration, the keyframe-to-frame registration, γ's inner products, and the
// rest of track() (fusion with the chain, the local graph, bookkeeping). Images are decoded before
// the clock starts; each frame is timed as the tracker sees it.
//
//   odometry_stages [SEQUENCE] [--frames N] [--set key=value]... [--out TRAJ.txt]
//
// SEQUENCE defaults to ../shared/data/tum/fr1_rpy (the committed 50-frame sample without it).
// Prints a table (median, p99 and mean ms per frame; the mean's share of the whole) and the
// solver's iterations. Speed is measured here, never asserted in tests; libcvo/odometry/README.md
// keeps the figures.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <numeric>
#include <string>
#include <vector>

#include "libcvo/config/config.hpp"
#include "libcvo/config/module_parameters.hpp"
#include "libcvo/core/units.hpp"
#include "libcvo/eval/percentile.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"
#include "program/cli.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;

struct Stage {
  const char* name;
  std::vector<double> ms;  // one per tracked frame
};

using eval::percentile;

double mean(const std::vector<double>& v) {
  return v.empty() ? 0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

void print_table(const std::vector<Stage>& stages, const std::vector<double>& iterations) {
  const double total = mean(stages.back().ms);
  std::printf("| stage | median ms | p99 ms | mean ms | share of the mean |\n| --- | --- | --- | --- | --- |\n");
  for (const auto& s : stages)
    std::printf("| %s | %.2f | %.2f | %.2f | %.0f %% |\n", s.name, percentile(s.ms, 50), percentile(s.ms, 99),
                mean(s.ms), total > 0 ? 100.0 * mean(s.ms) / total : 0.0);
  std::printf("\nsolver iterations per frame (both registrations): median %.0f, p99 %.0f\n", percentile(iterations, 50),
              percentile(iterations, 99));
}

int run(const fs::path& sequence_dir, std::size_t max_frames, const std::vector<std::string>& settings,
        const fs::path& out) {
  config::Config config;
  for (const auto& s : settings) config::apply_override(config, s);
  io::TumOptions options = config::tum_options(config);
  options.max_frames = max_frames;
  const auto sequence = io::TumSequence::open(sequence_dir, options);
  std::vector<core::RgbdFrame> frames;
  frames.reserve(sequence.size());
  for (std::size_t i = 0; i < sequence.size(); ++i) frames.push_back(sequence.read(i));

  const auto& camera = sequence.intrinsics();
  odometry::KeyframeOdometry tracker(camera.width, camera.height, config::keyframe_odometry_parameters(config));
  std::vector<Stage> stages{{"point selection", {}},       {"frame-to-frame registration", {}},
                            {"keyframe registration", {}}, {"γ inner products", {}},
                            {"rest of track()", {}},       {"whole frame", {}}};
  std::vector<double> iterations;
  std::size_t keyframes = 0;
  std::map<std::string, std::size_t> reasons;
  core::Trajectory trajectory;
  for (const auto& frame : frames) {
    const auto start = core::SteadyClock::now();
    const auto r = tracker.track(frame);
    const double whole = core::ms_since(start);
    trajectory.push_back({frame.timestamp, r.pose});
    keyframes += r.keyframe;
    if (r.keyframe) ++reasons[odometry::to_string(r.reason)];
    if (r.status != odometry::TrackStatus::kOk) continue;  // first frames and failures: not the steady state
    const double parts = r.selection_ms + r.frame_registration_ms + r.keyframe_registration_ms + r.gamma_ms;
    const double values[] = {r.selection_ms, r.frame_registration_ms,      r.keyframe_registration_ms,
                             r.gamma_ms,     std::max(0.0, whole - parts), whole};
    for (std::size_t i = 0; i < stages.size(); ++i) stages[i].ms.push_back(values[i]);
    iterations.push_back(r.iterations);
  }
  std::printf("%s: %zu frames, %zu tracked, %zu keyframes, cvo.threads %d\n\n", sequence_dir.string().c_str(),
              frames.size(), stages.back().ms.size(), keyframes, config.cvo.threads);
  print_table(stages, iterations);
  if (!out.empty()) io::write_tum_trajectory(out, trajectory);
  std::printf("keyframes by reason:");
  for (const auto& [why, n] : reasons) std::printf(" %s %zu;", why.c_str(), n);
  std::printf("\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app;
  cvo::program::describe(app, "odometry_stages [SEQUENCE] [--frames N] [--set key=value]... [--out TRAJ.txt]",
                         "Times KF-CVO stage by stage over a TUM RGB-D folder (images decoded first).");
  fs::path sequence = fs::path(CVO_SHARED_DATA_DIR) / "tum" / "fr1_rpy";
  if (!fs::exists(sequence / "rgb.txt")) sequence = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";
  std::size_t frames = 0;
  std::vector<std::string> settings;
  fs::path out;
  app.add_option("SEQUENCE", sequence, "TUM RGB-D folder");
  app.add_option("--out", out, "also write the trajectory (TUM format), for cvo-eval");
  app.add_option("--frames", frames, "only the first N frames (0: all)")->transform(cvo::program::kDecimal);
  cvo::program::add_set_option(app, settings, "cvo.threads=2");
  return cvo::program::cli_main(app, argc, argv, [&] { return run(sequence, frames, settings, out); });
}
