// pgo-bench FILE.g2o [--json] [--max-iterations N] [--robust] [--repeat N]
//
// Optimises one g2o pose graph twice from the same initial guess (the vertices as given), with
// the same gauge (FIX'ed vertices, or the first vertex when there are none) and the same iteration
// cap: once with cvo::posegraph (LM on SE(3), CHOLMOD) and once with Ceres Solver using the
// formulation of Ceres' examples/slam/pose_graph_3d (quaternion + translation blocks,
// EigenQuaternionManifold, SPARSE_NORMAL_CHOLESKY, LM), written out below.
//
// The two solvers minimise nearly the same residual (Ceres' example: [R_a^T (p_b - p_a) - p_ab;
// 2 vec(q_ab q_est^-1)], error in a's frame; ours, posegraph/residual.hpp: [t_E; 2 vec(q_E)] of
// E = T_ab^-1 T_a^-1 T_b, error in the measured b's frame). With an anisotropic information matrix
// the two frames weigh differently, so their own final costs are not exactly comparable. Every cost this tool prints is
// therefore posegraph::cost() evaluated on each solver's final poses: 1/2 sum rho(e^T Omega e) with our residual.
// Ceres' own figure is in the JSON as solver_cost. --robust puts a Cauchy kernel (delta = 2, Ceres' CauchyLoss(2)) on
// every edge in both.
//
// Information matrices that are not positive semi-definite are repaired by the reader, with one
// warning on standard error (g2o_io.hpp); --json counts them (repaired_information). CHOLMOD's
// own messages go to standard error too, so standard output holds only the report.
//
// Timing: before either solver is timed, both solve a small piece of the graph once, so that
// neither pays the process's one-off start-up costs (CHOLMOD's OpenMP thread pool, lazily bound
// symbols, first allocations) inside its figure; whichever ran first used to. --repeat N solves
// N times from the same guess, the two solvers taking turns, and reports each one's median time,
// for machines shared with other work.
//
// Exit status: 0 done, 1 bad input file, 2 bad command line.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <ceres/ceres.h>
#include <Eigen/Eigenvalues>

#include "libcvo/core/parameters.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/posegraph/cost.hpp"
#include "libcvo/posegraph/g2o_io.hpp"
#include "libcvo/posegraph/optimizer.hpp"
#include "program/cli.hpp"
#include "program/json.hpp"

namespace {

namespace program = cvo::program;
using cvo::posegraph::Edge;
using cvo::posegraph::NodeId;
using cvo::posegraph::PoseGraph;

struct Options {
  std::string file;
  bool json = false;
  bool robust = false;
  int max_iterations = 100;
  int repeat = 1;
};

struct Result {
  std::string solver;
  double initial_cost = 0;
  double final_cost = 0;
  double solver_cost = 0;  // the solver's own objective at the end
  int iterations = 0;
  int factorizations = 0;  // numeric factorisations (Ceres: linear solves, one each)
  double seconds = 0;
  bool converged = false;
  std::string stop_reason;
};

// Ceres' pose_graph_3d error term: residual sqrt(Omega) [R_a^T (p_b - p_a) - p_ab; 2 vec(q_ab q_est^-1)].
// sqrt(Omega) is the upper Cholesky factor U (U^T U = Omega), so that r^T r = e^T Omega e.
struct PoseGraph3dErrorTerm {
  Eigen::Vector3d p_ab;
  Eigen::Quaterniond q_ab;
  Eigen::Matrix<double, 6, 6> sqrt_information;

  template <typename T>
  bool operator()(const T* p_a_ptr, const T* q_a_ptr, const T* p_b_ptr, const T* q_b_ptr, T* residuals_ptr) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_a(p_a_ptr), p_b(p_b_ptr);
    const Eigen::Map<const Eigen::Quaternion<T>> q_a(q_a_ptr), q_b(q_b_ptr);
    const Eigen::Quaternion<T> q_a_inverse = q_a.conjugate();
    const Eigen::Quaternion<T> q_ab_estimated = q_a_inverse * q_b;
    const Eigen::Matrix<T, 3, 1> p_ab_estimated = q_a_inverse * (p_b - p_a);
    const Eigen::Quaternion<T> delta_q = q_ab.template cast<T>() * q_ab_estimated.conjugate();
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residuals(residuals_ptr);
    residuals.template head<3>() = p_ab_estimated - p_ab.template cast<T>();
    residuals.template tail<3>() = T(2.0) * delta_q.vec();
    residuals.applyOnTheLeft(sqrt_information.template cast<T>());
    return true;
  }
};

// A square root S (S^T S = Omega) that exists for every information the graph holds, semi-definite
// ones too (core/information.hpp), which have no Cholesky factor: V sqrt(Lambda) V^T, with round-off
// below zero clamped.
Eigen::Matrix<double, 6, 6> square_root(const Eigen::Matrix<double, 6, 6>& omega) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(omega);
  const Eigen::Matrix<double, 6, 6>& V = eigen.eigenvectors();
  return V * eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() * V.transpose();
}

Result run_ours(PoseGraph graph, const Options& options) {
  cvo::posegraph::OptimizerOptions o;
  o.pose_graph.max_iterations = options.max_iterations;
  const auto report = cvo::posegraph::optimize(graph, o);
  return {"cvo",
          report.initial_cost,
          cvo::posegraph::cost(graph),
          report.final_cost,
          report.iterations,
          report.factorizations,
          report.seconds,
          report.converged,
          report.stop_reason};
}

Result run_ceres(PoseGraph graph, const Options& options) {
  struct Block {
    Eigen::Vector3d p;
    Eigen::Quaterniond q;  // Eigen's storage (x, y, z, w), as EigenQuaternionManifold expects
  };
  std::map<NodeId, Block> blocks;
  for (const auto& [id, node] : graph.nodes()) blocks[id] = {node.pose.translation(), node.pose.rotation()};

  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::EigenQuaternionManifold quaternion_manifold;
  const double delta = cvo::core::PoseGraphParameters{}.cauchy_delta;
  for (const Edge& e : graph.edges()) {
    auto* cost = new ceres::AutoDiffCostFunction<PoseGraph3dErrorTerm, 6, 3, 4, 3, 4>(
        new PoseGraph3dErrorTerm{e.measurement.translation(), e.measurement.rotation(), square_root(e.information)});
    ceres::LossFunction* loss = e.robust ? new ceres::CauchyLoss(delta) : nullptr;
    Block& a = blocks.at(e.from);
    Block& b = blocks.at(e.to);
    problem.AddResidualBlock(cost, loss, a.p.data(), a.q.coeffs().data(), b.p.data(), b.q.coeffs().data());
    problem.SetManifold(a.q.coeffs().data(), &quaternion_manifold);
    problem.SetManifold(b.q.coeffs().data(), &quaternion_manifold);
  }
  // The same gauge as ours: FIX'ed vertices, or the first one.
  bool any_fixed = false;
  for (const auto& [id, node] : graph.nodes()) any_fixed = any_fixed || node.fixed;
  for (auto& [id, block] : blocks) {
    if (!(graph.node(id).fixed || (!any_fixed && id == blocks.begin()->first))) continue;
    if (!problem.HasParameterBlock(block.p.data())) continue;
    problem.SetParameterBlockConstant(block.p.data());
    problem.SetParameterBlockConstant(block.q.coeffs().data());
  }

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.num_threads = 1;  // like ours (and the GTSAM reference figures)
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);

  const cvo::posegraph::RobustKernel kernel;
  Result r{"ceres",
           cvo::posegraph::cost(graph, kernel),
           0,
           summary.final_cost,
           summary.num_successful_steps + summary.num_unsuccessful_steps,
           summary.num_linear_solves,
           summary.total_time_in_seconds,
           summary.termination_type == ceres::CONVERGENCE,
           summary.message};
  for (const auto& [id, block] : blocks) graph.set_pose(id, cvo::core::SE3(block.q, block.p));
  r.final_cost = cvo::posegraph::cost(graph, kernel);
  return r;
}

constexpr const char* kDescription =
    R"(Optimises the pose graph of FILE.g2o (VERTEX_SE3:QUAT / EDGE_SE3:QUAT) twice from the same initial
guess, first pose fixed: with cvo::posegraph (Levenberg-Marquardt on SE(3), CHOLMOD) and with Ceres
Solver (quaternion + translation blocks, sparse normal Cholesky). Both final costs are computed by
one function, 1/2 sum rho(e' Omega e) with e = [t_E; 2 vec(q_E)], E = Z^-1 Ti^-1 Tj.
An information matrix that is not positive semi-definite is replaced by the nearest positive-
definite one, with one warning on standard error.
)";

void add_options(CLI::App& app, Options& options) {
  app.add_option("FILE.g2o", options.file, "the pose graph")->required();
  app.add_flag("--json", options.json,
               "one JSON object: repaired_information (edges), per solver initial_cost, final_cost, iterations, "
               "seconds");
  app.add_option("--max-iterations", options.max_iterations, "iteration cap of both solvers")
      ->transform(program::kDecimal)
      ->check(CLI::Range(1, 1000000));
  app.add_flag("--robust", options.robust, "Cauchy kernel (delta 2) on every edge");
  app.add_option("--repeat", options.repeat, "solve N times each and report the median time")
      ->transform(program::kDecimal)
      ->check(CLI::Range(1, 1000));
}

// The first nodes (up to 20, by id) and the edges among them: a problem that starts up what each
// solver uses without taking measurable time.
PoseGraph warm_up_piece(const PoseGraph& graph) {
  PoseGraph piece;
  for (const auto& [id, node] : graph.nodes()) {
    if (piece.nodes().size() == 20) break;
    piece.add_node(id, node.pose, node.fixed);
  }
  for (const Edge& e : graph.edges())
    if (piece.contains(e.from) && piece.contains(e.to)) piece.add_edge(e);
  return piece;
}

// Both solvers `repeat` times from the same graph, taking turns (ours, Ceres, ours, ...) so that
// a machine whose speed drifts slows both alike; each one's last result, with its median time.
std::array<Result, 2> timed_side_by_side(const PoseGraph& graph, const Options& options) {
  std::array<std::vector<double>, 2> seconds;
  std::array<Result, 2> results;
  for (int k = 0; k < options.repeat; ++k) {
    results[0] = run_ours(graph, options);
    results[1] = run_ceres(graph, options);
    for (std::size_t s = 0; s < 2; ++s) seconds[s].push_back(results[s].seconds);
  }
  for (std::size_t s = 0; s < 2; ++s) {
    auto& t = seconds[s];
    std::nth_element(t.begin(), t.begin() + options.repeat / 2, t.end());
    results[s].seconds = t[static_cast<std::size_t>(options.repeat / 2)];
  }
  return results;
}

program::Json report_json(const Options& options, const PoseGraph& graph, const cvo::posegraph::G2oRepairs& repairs,
                          const std::array<Result, 2>& results) {
  program::Json o;
  o["file"] = options.file;
  o["nodes"] = graph.nodes().size();
  o["edges"] = graph.edges().size();
  o["repaired_information"] = repairs.edges;
  o["robust"] = options.robust;
  o["max_iterations"] = options.max_iterations;
  o["repeat"] = options.repeat;
  program::Json& solvers = o["solvers"] = program::Json::object();
  for (const Result& r : results)
    solvers[r.solver] = {{"initial_cost", r.initial_cost}, {"final_cost", r.final_cost},
                         {"iterations", r.iterations},     {"factorizations", r.factorizations},
                         {"seconds", r.seconds},           {"converged", r.converged},
                         {"solver_cost", r.solver_cost},   {"stop_reason", r.stop_reason}};
  return o;
}

int run(const Options& options) {
  cvo::posegraph::send_cholmod_messages_to_stderr();  // before Ceres starts CHOLMOD too
  cvo::posegraph::G2oRepairs repairs;
  PoseGraph graph = cvo::posegraph::read_g2o(options.file, std::cerr, &repairs);
  if (options.robust) {
    PoseGraph robust;
    for (const auto& [id, node] : graph.nodes()) robust.add_node(id, node.pose, node.fixed);
    for (Edge e : graph.edges()) {
      e.robust = true;
      robust.add_edge(e);
    }
    graph = std::move(robust);
  }
  const PoseGraph piece = warm_up_piece(graph);
  if (!piece.edges().empty()) {
    run_ours(piece, options);
    run_ceres(piece, options);
  }
  const std::array<Result, 2> results = timed_side_by_side(graph, options);

  if (options.json) {
    std::cout << program::to_text(report_json(options, graph, repairs, results));
    return 0;
  }
  std::printf("%s: %zu nodes, %zu edges, %s, at most %d iterations; cost = 1/2 sum rho(chi2), our residual\n",
              options.file.c_str(), graph.nodes().size(), graph.edges().size(),
              options.robust ? "Cauchy(2) on every edge" : "plain least squares", options.max_iterations);
  std::printf("%-6s %14s %16s %10s %14s %9s  %s\n", "solver", "initial_cost", "final_cost", "iterations",
              "factorizations", "seconds", "stop");
  for (const Result& r : results)
    std::printf("%-6s %14.6g %16.10g %10d %14d %9.3f  %s\n", r.solver.c_str(), r.initial_cost, r.final_cost,
                r.iterations, r.factorizations, r.seconds, r.stop_reason.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app(kDescription, "pgo-bench");
  program::describe(app, "pgo-bench FILE.g2o [--json] [--max-iterations N] [--robust] [--repeat N]");
  add_options(app, options);
  return program::cli_main(app, argc, argv, [&] { return run(options); });
}
