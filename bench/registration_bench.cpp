// Speed of the registration core on real consecutive fr1/rpy frames: point selection, one align()
// (the tracker's case: guess = previous motion), one inner_product(); scalar vs AVX2, 1 vs 2
// threads. Uses ../shared/data/tum/fr1_rpy when present, else the committed 50-frame sample.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <vector>

#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/registration/point_selection.hpp"
#include "libcvo/registration/registration.hpp"

namespace {

using namespace cvo;

constexpr std::size_t kFrames = 40;

struct Data {
  std::vector<core::RgbdFrame> frames;
  std::vector<std::unique_ptr<registration::PointCloud>> clouds;
  // The same points with every label alike: a white room's worst case, geometry alone (issue 47).
  std::vector<std::unique_ptr<registration::PointCloud>> alike;
  std::vector<core::SE3> guesses;  // guess for pair (i, i+1): the motion found for (i-1, i)
};

const Data& data() {
  static const Data d = [] {
    Data out;
    std::filesystem::path dir = std::filesystem::path(CVO_SHARED_DATA_DIR) / "tum" / "fr1_rpy";
    if (!std::filesystem::exists(dir / "rgb.txt")) dir = std::filesystem::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";
    auto sequence = io::TumSequence::open(dir);
    registration::PointSelector selector(640, 480, core::SelectionParameters{});
    while (out.frames.size() < kFrames) {
      auto frame = sequence.next();
      if (!frame) break;
      out.clouds.push_back(std::make_unique<registration::PointCloud>(8192));
      selector.select(*frame, *out.clouds.back());
      const auto& cloud = *out.clouds.back();
      out.alike.push_back(std::make_unique<registration::PointCloud>(8192));
      for (std::size_t i = 0; i < cloud.size(); ++i)
        out.alike.back()->push_back(cloud.position(i), registration::Feature{0.8f, 0.8f, 0.8f, 0.0f, 0.0f});
      out.frames.push_back(std::move(*frame));
    }
    registration::Registration reg(registration::Capacities{8192}, core::CvoParameters{});
    core::SE3 velocity;
    for (std::size_t i = 0; i + 1 < out.clouds.size(); ++i) {
      out.guesses.push_back(velocity);
      velocity = reg.align(*out.clouds[i], *out.clouds[i + 1], velocity).transform;
    }
    return out;
  }();
  return d;
}

// Arg: 1 = the frames' own camera (fr1: rays from the undistortion table), 0 = the same frames
// with the lens coefficients zeroed (rays by division), to compare the two back-projections.
void BM_PointSelection(benchmark::State& state) {
  auto frames = data().frames;  // shallow image copies
  if (state.range(0) == 0)
    for (auto& f : frames) f.intrinsics.distortion = {};
  registration::PointSelector selector(640, 480, core::SelectionParameters{});
  registration::PointCloud cloud(8192);
  selector.select(frames[0], cloud);  // warm-up: builds the ray table once, outside the timing
  std::size_t i = 0, points = 0;
  for (auto _ : state) {
    const auto r = selector.select(frames[i++ % frames.size()], cloud);
    points += r.selected;
  }
  state.counters["points"] = benchmark::Counter(static_cast<double>(points), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_PointSelection)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Args: {isa: 0 scalar / 1 SIMD, threads, reading: 0 = σ, σ_c as standard deviations (default),
//        1 = as variances (σ = sqrt(0.1), the looser reading compared in core/parameters.hpp),
//        2 = the default with every label alike (Data::alike),
//        candidate pairs per point (registration.hpp's budget; 0: every iteration searches the cells)}
void BM_Align(benchmark::State& state) {
  const auto& d = data();
  // 1: the SIMD kernel this machine has (AVX2+FMA or NEON).
  const auto isa = state.range(0) ? registration::kernel::best_isa() : registration::kernel::Isa::kScalar;
  if (state.range(0) && isa == registration::kernel::Isa::kScalar) {
    state.SkipWithError("no SIMD kernel on this CPU/build");
    return;
  }
  core::CvoParameters parameters;
  parameters.threads = static_cast<int>(state.range(1));
  if (state.range(2) == 1) parameters.sigma = std::sqrt(0.1);
  registration::Registration reg(registration::Capacities{8192, static_cast<std::size_t>(state.range(3))}, parameters,
                                 isa);
  std::size_t i = 0;
  double iterations = 0, pairs = 0;
  for (auto _ : state) {
    const std::size_t k = i++ % d.guesses.size();
    const auto& clouds = state.range(2) == 2 ? d.alike : d.clouds;
    const auto r = reg.align(*clouds[k], *clouds[k + 1], d.guesses[k]);
    iterations += r.iterations;
    for (std::size_t q = 0; q < reg.pairs_logged(); ++q) pairs += static_cast<double>(reg.pairs_per_iteration()[q]);
  }
  state.counters["iterations"] = benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
  // Inverted rate of iterations/1000: milliseconds per solver iteration (printed with an "s").
  state.counters["ms_per_iteration"] =
      benchmark::Counter(iterations / 1e3, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["pairs_per_iteration"] = benchmark::Counter(pairs / std::max(iterations, 1.0));
  state.counters["pairs_per_s"] = benchmark::Counter(pairs, benchmark::Counter::kIsRate);
  state.SetLabel(std::string(registration::kernel::to_string(isa)) + ", " + std::to_string(parameters.threads) +
                 " thread(s)" + (state.range(2) == 1 ? ", variance reading" : "") +
                 (state.range(2) == 2 ? ", every label alike" : "") +
                 (state.range(3) == 0 ? ", no candidate pairs" : ""));
}
BENCHMARK(BM_Align)
    ->Args({0, 1, 0, 32})
    ->Args({1, 1, 0, 0})
    ->Args({1, 1, 0, 32})
    ->Args({1, 2, 0, 32})
    ->Args({1, 1, 1, 32})
    ->Args({1, 1, 2, 0})
    ->Args({1, 1, 2, 32})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_InnerProduct(benchmark::State& state) {
  const auto& d = data();
  registration::Registration reg(registration::Capacities{8192}, core::CvoParameters{});
  std::size_t i = 0;
  for (auto _ : state) {
    const std::size_t k = i++ % d.guesses.size();
    benchmark::DoNotOptimize(reg.inner_product(*d.clouds[k], *d.clouds[k + 1], d.guesses[k]));
  }
}
BENCHMARK(BM_InnerProduct)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
