// Revisits that do not grow the map (issue #27 item 3, slam/mapper.hpp): a second visit of the
// embedded sample is merged into the first visit's keyframes.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include "tests/drivers/tum_copy.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::slam {
namespace {

namespace fs = std::filesystem;
using cvo::testing::json_value;
using cvo::testing::quoted;
using cvo::testing::run_tool;
using cvo::testing::ToolRun;

struct Pose {
  Eigen::Vector3d t;
  Eigen::Quaterniond q;
};

// The first `n` poses of a TUM trajectory file.
std::vector<Pose> first_poses(const fs::path& file, std::size_t n) {
  std::vector<Pose> poses;
  std::ifstream in(file);
  for (std::string line; poses.size() < n && std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    double stamp = 0;
    Pose p;
    fields >> stamp >> p.t.x() >> p.t.y() >> p.t.z() >> p.q.x() >> p.q.y() >> p.q.z() >> p.q.w();
    poses.push_back(p);
  }
  return poses;
}

ToolRun visits(const test::TempDir& dir, int n, const std::string& name) {
  std::string sequences;
  for (int k = 0; k < n; ++k) sequences += quoted(test::kSample) + " ";
  return run_tool("cvo-run", sequences + "--mode slam --json --out " + quoted(dir.path() / name), dir.path());
}

// The second visit adds one node: its final leaf (the last frame of its open local graph, no
// keyframe). Every keyframe is merged: without the merge each would be a node (as many as the first
// visit's); without its first keyframe's search at its successor (LoopDetector::detect_first) that
// one would be; and without confirmations (a view the current estimate explains as well as CVO,
// refused as a loop by α: an exact replay's images are the same) some others would.
// The first visit's poses: the second adds the same registrations again (fused), so they move by
// far less than the map's own error (the sample's ATE is ~1.5 cm): 2 cm and 1 degree.
TEST(Revisit, EveryKeyframeOfASecondVisitOfTheSampleIsMergedAndTheMapStaysInPlace) {
  const test::TempDir dir("cvo_run_revisit");
  const ToolRun one = visits(dir, 1, "one.txt");
  const ToolRun two = visits(dir, 2, "two.txt");
  ASSERT_EQ(one.exit_code, 0) << one.err;
  ASSERT_EQ(two.exit_code, 0) << two.err;
  const int keyframes = std::stoi(json_value(one.out, "keyframes"));
  const int nodes_one = std::stoi(json_value(one.out, "graph_nodes"));
  const int nodes_two = std::stoi(json_value(two.out, "graph_nodes"));
  std::printf("one visit: %d keyframes, %d graph nodes; two visits: %d graph nodes, %s keyframes merged\n", keyframes,
              nodes_one, nodes_two, json_value(two.out, "keyframes_merged").c_str());
  EXPECT_LE(nodes_two - nodes_one, 1);
  EXPECT_EQ(std::stoi(json_value(two.out, "keyframes_merged")), keyframes);

  const auto single = first_poses(dir.path() / "one.txt", 50);
  const auto revisited = first_poses(dir.path() / "two.txt", 50);  // the first session's frames come first
  ASSERT_EQ(single.size(), 50u);
  ASSERT_EQ(revisited.size(), 50u);
  double worst_m = 0, worst_deg = 0;
  for (std::size_t i = 0; i < single.size(); ++i) {
    worst_m = std::max(worst_m, (single[i].t - revisited[i].t).norm());
    worst_deg = std::max(worst_deg, single[i].q.angularDistance(revisited[i].q) * 180 / M_PI);
  }
  std::printf("the first visit's frames moved by at most %.2f mm and %.3f deg\n", 1e3 * worst_m, worst_deg);
  EXPECT_LT(worst_m, 0.02);
  EXPECT_LT(worst_deg, 1.0);
}

}  // namespace
}  // namespace cvo::slam
