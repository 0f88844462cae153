// The small standard benchmarks from ../shared/data/posegraph (skipped when absent).
#include <filesystem>

#include <gtest/gtest.h>

#include "libcvo/posegraph/cost.hpp"
#include "libcvo/posegraph/g2o_io.hpp"
#include "libcvo/posegraph/optimizer.hpp"

namespace cvo::posegraph {
namespace {

std::filesystem::path dataset(const std::string& name) {
  return std::filesystem::path(CVO_SHARED_DATA_DIR) / "posegraph" / (name + ".g2o");
}

class SharedPoseGraph : public ::testing::TestWithParam<const char*> {};

TEST_P(SharedPoseGraph, CostDecreasesAndConverges) {
  const auto file = dataset(GetParam());
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data absent: " << file;
  PoseGraph graph = read_g2o(file);
  const auto report = optimize(graph);
  EXPECT_TRUE(report.converged) << report.stop_reason;
  EXPECT_LT(report.final_cost, 0.5 * report.initial_cost);
  EXPECT_NEAR(report.final_cost, cost(graph), 1e-9 * report.final_cost);
  double previous = report.initial_cost;
  for (const auto& record : report.log) {
    EXPECT_LE(record.cost, previous);  // LM only keeps steps that lower the cost
    previous = record.cost;
  }
  // Once converged the gradient is ~0: one more run makes no real progress.
  const auto again = optimize(graph);
  EXPECT_NEAR(again.final_cost, report.final_cost, 1e-5 * report.final_cost);
}

INSTANTIATE_TEST_SUITE_P(Grids, SharedPoseGraph, ::testing::Values("tinyGrid3D", "smallGrid3D"));

// The GTSAM 4.3 reference (shared/reference/anchors.md): 1/2 chi^2 = 0.634 with the first pose
// fixed; the same residual and information convention give the same minimum.
TEST(SharedPoseGraph, ParkingGarageReachesTheReferenceCost) {
  const auto file = dataset("parking-garage");
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data absent: " << file;
  PoseGraph graph = read_g2o(file);
  const auto report = optimize(graph);
  EXPECT_TRUE(report.converged) << report.stop_reason;
  EXPECT_NEAR(report.final_cost, 0.634, 0.001);
}

// torus3D starts far from its minimum (rotation errors near pi on some edges). With the SE(3)
// logarithm as residual, LM stops at 29 950 (GTSAM's figure in anchors.md too); with the residual
// of residual.hpp it reaches the minimum Ceres finds from the same guess: 22 556.2, measured with
// `pgo-bench torus3D.g2o`, which evaluates both solvers' poses with this cost. ~25 s in Release.
TEST(SharedPoseGraph, Torus3DReachesTheMinimumCeresFinds) {
  const auto file = dataset("torus3D");
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data absent: " << file;
  PoseGraph graph = read_g2o(file);
  const auto report = optimize(graph);
  EXPECT_TRUE(report.converged) << report.stop_reason;
  EXPECT_NEAR(report.final_cost, 22556.2, 0.001 * 22556.2);
}

}  // namespace
}  // namespace cvo::posegraph
