// Incremental against batch pose-graph optimisation after each loop, on simulated patrols of
// 10^2, 10^3 and 10^4 nodes (libcvo/sim/patrol_graph.hpp), side by side in one run: each node
// arrives with its edges (libcvo/posegraph/arrivals.hpp) and IncrementalOptimizer::update() runs;
// at a loop, the batch Optimizer (one kept for the run: its symbolic analysis is reused) also
// re-optimises the same graph from the same poses, on a copy. Prints one table.
// Run: build/release/bin/incremental_bench [--batch-samples N] [--max-nodes N] [--threshold X] [--rebuild-fraction F]
//   batch runs per size (spread over the loops), the largest patrol, IncrementalOptions' relinearise_threshold and
//   rebuild_fraction.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "libcvo/eval/percentile.hpp"
#include "libcvo/posegraph/arrivals.hpp"
#include "libcvo/posegraph/incremental_optimizer.hpp"
#include "libcvo/posegraph/optimizer.hpp"
#include "libcvo/sim/patrol_graph.hpp"

namespace {

using namespace cvo;
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

struct Row {
  std::size_t nodes = 0, loops = 0, rebuilds = 0;
  std::vector<double> loop_ms, odometry_ms, loop_columns, batch_ms;
  double incremental_cost = 0, converged_cost = 0, batch_cost = 0;
  std::size_t factor_columns = 0;
};

Row run(std::size_t route_poses, std::size_t laps, std::size_t batch_samples, const posegraph::IncrementalOptions& io) {
  sim::PatrolOptions options;
  options.route_poses = route_poses;
  options.laps = laps;
  const sim::PatrolGraph patrol = sim::patrol_graph(options);
  Row row;
  row.nodes = patrol.truth.size();
  row.loops = patrol.loops;
  const std::size_t every = std::max<std::size_t>(1, patrol.loops / std::max<std::size_t>(batch_samples, 1));
  posegraph::IncrementalOptimizer incremental(io);
  posegraph::Optimizer batch;
  std::size_t loop_index = 0;
  for (const auto& arrival : posegraph::arrivals(patrol.graph)) {
    posegraph::add_arrival(incremental, arrival, patrol.graph.node(arrival.node).pose);
    const bool loop = arrival.edges.size() > 1;
    if (loop && loop_index++ % every == 0) {
      posegraph::PoseGraph graph = incremental.graph();  // the poses before this loop, the loop in
      const auto start = Clock::now();
      batch.optimize(graph);
      row.batch_ms.push_back(ms_since(start));
    }
    const auto start = Clock::now();
    const auto report = incremental.update();
    (loop ? row.loop_ms : row.odometry_ms).push_back(ms_since(start));
    if (loop) row.loop_columns.push_back(static_cast<double>(report.touched_columns));
    row.rebuilds += report.rebuilt ? 1 : 0;
  }
  row.factor_columns = incremental.factor_columns();
  row.incremental_cost = incremental.cost();
  for (int k = 0; k < 200 && incremental.update().max_step > 1e-7; ++k) {
  }
  row.converged_cost = incremental.cost();
  posegraph::PoseGraph graph = patrol.graph;
  row.batch_cost = batch.optimize(graph).final_cost;
  return row;
}

double p(std::vector<double> v, double q) { return eval::percentile_in_place(v, q); }

}  // namespace

int main(int argc, char** argv) {
  std::size_t batch_samples = 30, max_nodes = 10000;
  posegraph::IncrementalOptions io;
  for (int k = 1; k + 1 < argc; ++k) {
    const std::string flag = argv[k];
    if (flag == "--batch-samples") batch_samples = std::strtoul(argv[k + 1], nullptr, 10);
    if (flag == "--max-nodes") max_nodes = std::strtoul(argv[k + 1], nullptr, 10);
    if (flag == "--threshold") io.relinearise_threshold = std::strtod(argv[k + 1], nullptr);
    if (flag == "--rebuild-fraction") io.rebuild_fraction = std::strtod(argv[k + 1], nullptr);
  }
  std::printf(
      "| nodes | loops | incremental loop update ms p50 / p99 | odometry update ms p50 / p99 | columns touched by a "
      "loop p50 / p99 (of) | rebuilds | batch after a loop ms p50 / p99 (runs) | final cost incremental / after final "
      "updates / batch |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (const auto& [route, laps] : {std::pair<std::size_t, std::size_t>{50, 2}, {250, 4}, {2500, 4}}) {
    if (route * laps > max_nodes) break;
    const Row r = run(route, laps, batch_samples, io);
    std::printf(
        "| %zu | %zu | %.3f / %.3f | %.3f / %.3f | %.0f / %.0f (%zu) | %zu | %.2f / %.2f (%zu) | %.4f / %.4f / %.4f "
        "|\n",
        r.nodes, r.loops, p(r.loop_ms, 50), p(r.loop_ms, 99), p(r.odometry_ms, 50), p(r.odometry_ms, 99),
        p(r.loop_columns, 50), p(r.loop_columns, 99), r.factor_columns, r.rebuilds, p(r.batch_ms, 50),
        p(r.batch_ms, 99), r.batch_ms.size(), r.incremental_cost, r.converged_cost, r.batch_cost);
    std::fflush(stdout);
  }
}
