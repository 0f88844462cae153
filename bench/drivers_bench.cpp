// What a driver adds to each frame before it leaves: depth registration of a separate depth sensor.
// Run: build/release/bin/drivers_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include "drivers/depth_registration.hpp"
#include "libcvo/core/units.hpp"
#include "libcvo/sim/camera_path.hpp"
#include "libcvo/sim/render.hpp"
#include "libcvo/sim/scene.hpp"

namespace {

using namespace cvo;

// A RealSense D435-like pair: 848x480 depth (1 mm units) registered into 640x480 colour.
void BM_DepthRegistrationD435(benchmark::State& state) {
  const core::Intrinsics colour{615.0, 615.0, 319.5, 239.5, 640, 480, 1000.0, {}};
  const core::DepthSensor depth{
      {425.0, 425.0, 423.5, 239.5, 848, 480, 1000.0, {}},
      core::SE3::from_rotation_vector({0, core::radians(1.0), 0}) * core::SE3::from_translation({-0.015, 0, 0})};
  const auto frame = sim::render_separate_depth(sim::make_scene(sim::SceneKind::textured_room, 7), colour, depth,
                                                sim::path_pose(sim::PathKind::orbit, 3.0));
  const drivers::DepthRegistration registration(depth, colour);
  cv::Mat registered;
  for (auto _ : state) {
    registration.apply(frame.depth, registered);
    benchmark::DoNotOptimize(registered.data);
  }
}
BENCHMARK(BM_DepthRegistrationD435)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
