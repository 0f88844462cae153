#pragma once
// Levenberg-Marquardt on SE(3)^n for a PoseGraph, sparse normal equations solved by CHOLMOD.
//
// Each iteration linearises every edge (residual [t; log R] of Z^-1 T_i^-1 T_j, update T (+) delta =
// (R exp(phi), t + R rho), exact Jacobians: residual.hpp), weights it by IRLS (w = rho'(chi^2), see cost.hpp) and
// assembles
//   H = sum w J^T Omega J,  g = sum w J^T Omega e
// over the free nodes only: fixed nodes are removed from the system, and when no node is fixed
// the first (lowest id) is held, which fixes the gauge. It then solves (H + lambda D) delta = -g,
// D = diag(H) (clamped below, Marquardt's scaling), applies T_k <- T_k (+) delta_k and keeps the
// step if the cost went down; lambda follows Nielsen's rule (gain ratio r: lambda *= max(1/3,
// 1 - (2r - 1)^3) on success, lambda *= nu, nu *= 2 on failure).
//
// H is a cholmod_sparse upper triangle made of 6x6 blocks, assembled in place: each edge's three
// blocks have known positions in its values, and a new lambda rewrites only the diagonal (the
// undamped one is kept aside), so a rejected step re-uses the assembled H. The symbolic analysis
// runs once per graph structure, on the block pattern (AMD, and METIS / nested dissection when
// the factor is large, whichever fills less; each block's 6 columns kept together), and an
// Optimizer keeps it between calls, so a graph that grows (add_node / add_edge between optimise
// calls) is re-analysed only when its sparsity pattern changed.
//
// Factorisations are the cost (an iteration's assembly and cost evaluation are tens of times
// cheaper on the larger graphs). Near a minimum H changes little between linearisations, so the step is
// first sought by conjugate gradients on (H + lambda D) d = -g preconditioned by the factor at
// hand, to a relative residual of 1e-3, which is the LM step for all that the stopping test can
// tell. That is tried once the last step lowered the cost by less than 10 %, with a budget of
// PCG iterations set by the factorisation's flop count (from the analysis) against one PCG
// iteration's, and while the last iteration's solve work stays below the average per iteration
// since the last factorisation; otherwise, or when PCG does not converge, the damped H is
// refactorised. The factor survives between calls, so a second optimise of a graph that changed
// little may need no factorisation at all. OptimizerOptions::reuse_factorization = false turns
// PCG off: one factorisation per lambda trial, as plain LM.
#include <chrono>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "libcvo/core/parameters.hpp"
#include "libcvo/posegraph/cost.hpp"
#include "libcvo/posegraph/pose_graph.hpp"

namespace cvo::posegraph {

namespace detail {
struct Cholmod;
struct BlockPattern;
}  // namespace detail

struct OptimizerOptions {
  // Of the core struct (libcvo/core/parameters.hpp) max_iterations, and cauchy_delta for the edges
  // marked robust; bridge_information is the back end's.
  core::PoseGraphParameters pose_graph{};
  double relative_decrease = 1e-6;  // stop when an accepted step lowers the cost by less than this fraction
  double step_tolerance = 1e-10;    // stop when |delta| falls below this
  double initial_lambda = 1e-5;
  bool reuse_factorization = true;  // PCG on the factor at hand before refactorising (see above)
  // A time budget (cvo-backendd's stop within its unit's TimeoutStopSec): no new iteration starts
  // once this much has passed since optimize() was called, and the poses are those of the last
  // accepted step (each one lowered the cost, so they are never worse than the start). The
  // default is no limit.
  double max_seconds = std::numeric_limits<double>::infinity();
};

/// OptimizationReport::stop_reason of a run that max_seconds cut short.
inline constexpr const char* kTimeLimit = "time limit";

struct IterationRecord {
  double cost = 0;                    // after the iteration
  double lambda = 0;                  // the damping of the accepted (or last tried) step
  int trials = 0;                     // factorisations this iteration needed (more than one when steps were rejected)
  bool reused_factorization = false;  // the step came by PCG from an earlier factor (trials 0)
};

struct OptimizationReport {
  double initial_cost = 0;
  double final_cost = 0;
  int iterations = 0;      // linearisations; each may hold several lambda trials
  int factorizations = 0;  // numeric factorisations, over all iterations
  double seconds = 0;
  bool converged = false;
  std::string stop_reason;
  bool reanalysed = false;  // whether this call ran a new symbolic analysis
  std::vector<IterationRecord> log;
};

class Optimizer {
 public:
  explicit Optimizer(OptimizerOptions options = {});
  ~Optimizer();
  Optimizer(Optimizer&&) noexcept;
  Optimizer& operator=(Optimizer&&) noexcept;
  Optimizer(const Optimizer&) = delete;
  Optimizer& operator=(const Optimizer&) = delete;

  /// Optimises the poses of the graph's free nodes in place.
  OptimizationReport optimize(PoseGraph& graph);

  /// How many symbolic analyses this optimiser has run (one per distinct structure seen in a row).
  [[nodiscard]] int symbolic_analyses() const { return analyses_; }
  [[nodiscard]] const OptimizerOptions& options() const { return options_; }

 private:
  // Adopts the pattern; a new matrix and symbolic analysis only when it differs from the last one.
  // Returns whether it analysed.
  bool prepare_structure(std::unique_ptr<detail::BlockPattern> pattern);
  [[nodiscard]] std::chrono::steady_clock::time_point deadline(std::chrono::steady_clock::time_point start) const;

  OptimizerOptions options_;
  std::unique_ptr<detail::Cholmod> cholmod_;
  std::unique_ptr<detail::BlockPattern> pattern_;
  int analyses_ = 0;
};

/// One-shot convenience: a fresh Optimizer.
OptimizationReport optimize(PoseGraph& graph, const OptimizerOptions& options = {});

/// CHOLMOD prints through one process-wide printf, to standard output by default, which puts its
/// messages ("matrix not positive definite") in the middle of a program's output (pgo-bench
/// --json). This points it at standard error, the log, for every CHOLMOD user in the process
/// (Ceres too). Every Optimizer calls it; a program that uses CHOLMOD through another library
/// calls it first. Idempotent and thread-safe.
void send_cholmod_messages_to_stderr();

}  // namespace cvo::posegraph
