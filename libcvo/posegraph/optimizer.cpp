#include "libcvo/posegraph/optimizer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "libcvo/posegraph/cholmod_handles.hpp"
#include "libcvo/posegraph/residual.hpp"

namespace cvo::posegraph {

namespace detail {

// The sparsity of H: which 6x6 blocks exist. Block column C holds block rows column_blocks[C]
// (sorted, all <= C, the last one C itself); column 6C + c of the upper triangle then holds
// 6 rows for every off-diagonal block and c + 1 rows of the diagonal block.
struct BlockPattern {
  std::vector<NodeId> free_ids;
  std::vector<std::vector<int>> column_blocks;

  bool operator==(const BlockPattern&) const = default;
};

}  // namespace detail

namespace {

using detail::BlockPattern;

using core::Matrix6d;
using core::SE3;
using core::Vector6d;
using Index = SuiteSparse_long;

// The graph in dense indices: node k of the id-ordered map is poses[k]; var[k] is its block in H
// or -1 when it is held.
struct Problem {
  std::vector<SE3> poses;
  std::vector<int> var;
  struct DenseEdge {
    int i, j;
    const Edge* edge;
  };
  std::vector<DenseEdge> edges;
};

Problem make_problem(const PoseGraph& graph) {
  Problem p;
  std::unordered_map<NodeId, int> index;
  const bool any_fixed =
      std::any_of(graph.nodes().begin(), graph.nodes().end(), [](const auto& kv) { return kv.second.fixed; });
  int next_var = 0;
  for (const auto& [id, node] : graph.nodes()) {
    const bool held = node.fixed || (!any_fixed && p.poses.empty());  // gauge: hold the first node
    index.emplace(id, static_cast<int>(p.poses.size()));
    p.poses.push_back(node.pose);
    p.var.push_back(held ? -1 : next_var++);
  }
  for (const Edge& e : graph.edges()) p.edges.push_back({index.at(e.from), index.at(e.to), &e});
  return p;
}

double problem_cost(const Problem& p, const std::vector<SE3>& poses, const RobustKernel& kernel) {
  double sum = 0;
  for (const auto& de : p.edges) {
    const Vector6d e = edge_residual(poses[de.i], poses[de.j], de.edge->measurement);
    sum += kernel.rho(e.dot(de.edge->information * e), de.edge->robust);
  }
  return 0.5 * sum;
}

std::unique_ptr<BlockPattern> make_pattern(const PoseGraph& graph, const Problem& problem) {
  auto owned = std::make_unique<BlockPattern>();
  BlockPattern& pattern = *owned;
  for (std::size_t k = 0; const auto& kv : graph.nodes())
    if (problem.var[k++] >= 0) pattern.free_ids.push_back(kv.first);
  const auto n = pattern.free_ids.size();
  pattern.column_blocks.resize(n);
  for (const auto& de : problem.edges) {
    const int a = problem.var[de.i], b = problem.var[de.j];
    if (a >= 0 && b >= 0 && a != b) pattern.column_blocks[std::max(a, b)].push_back(std::min(a, b));
  }
  for (std::size_t c = 0; c < n; ++c) {
    auto& rows = pattern.column_blocks[c];
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    rows.push_back(static_cast<int>(c));
  }
  return owned;
}

// The upper triangle of H with the pattern's structure (values zero). With blocks_only, the n x n
// pattern of the blocks instead, for the ordering.
cholmod_sparse* allocate_matrix(const BlockPattern& pattern, bool blocks_only, cholmod_common* cc) {
  const auto n = static_cast<int>(pattern.column_blocks.size());
  const int b = blocks_only ? 1 : 6;
  std::size_t nnz = 0;
  for (const auto& rows : pattern.column_blocks) nnz += blocks_only ? rows.size() : 36 * (rows.size() - 1) + 21;
  const auto dim = static_cast<std::size_t>(b * n);
  cholmod_sparse* A = cholmod_l_allocate_sparse(dim, dim, nnz, /*sorted=*/1, /*packed=*/1, /*stype=upper*/ 1,
                                                blocks_only ? CHOLMOD_PATTERN : CHOLMOD_REAL, cc);
  if (A == nullptr) throw std::runtime_error("pose graph: CHOLMOD could not allocate H");
  auto* Ap = static_cast<Index*>(A->p);
  auto* Ai = static_cast<Index*>(A->i);
  Index pos = 0;
  for (int C = 0; C < n; ++C)
    for (int c = 0; c < b; ++c) {
      Ap[b * C + c] = pos;
      for (const int R : pattern.column_blocks[C])
        for (int r = 0; r < (R < C ? b : c + 1); ++r) Ai[pos++] = b * R + r;
    }
  Ap[b * n] = pos;
  if (!blocks_only) std::fill_n(static_cast<double*>(A->x), nnz, 0.0);
  return A;
}

// Dissection orderings pay off only on large factors: below this many flops (of the block
// pattern's factor, ~1/216 of H's), AMD alone is used.
constexpr double kDissectionFlops = 5e5;

// The fill-reducing ordering of the blocks, on the n x n block pattern (36 times smaller than H,
// so cheap): AMD, and on graphs whose factor is large METIS and nested dissection too, CHOLMOD
// keeping the best (less fill: on torus3D METIS needs ~30 % fewer flops than AMD). Each block's 6
// columns then follow their block, so supernodes never split a block.
std::vector<Index> block_ordering(detail::Cholmod& cholmod, const BlockPattern& pattern) {
  cholmod_common* cc = cholmod.common.get();
  const detail::SparsePtr blocks = cholmod.wrap(allocate_matrix(pattern, /*blocks_only=*/true, cc));
  cc->nmethods = 1;
  cc->method[0].ordering = CHOLMOD_AMD;
  detail::FactorPtr factor = cholmod.wrap(cholmod_l_analyze(blocks.get(), cc));
  if (factor && cc->fl > kDissectionFlops) {
    cc->nmethods = 3;
    cc->method[1].ordering = CHOLMOD_METIS;
    cc->method[2].ordering = CHOLMOD_NESDIS;
    factor = cholmod.wrap(cholmod_l_analyze(blocks.get(), cc));
  }
  if (!factor) throw std::runtime_error("pose graph: CHOLMOD analysis failed");
  const auto* P = static_cast<const Index*>(factor->Perm);
  const auto n = pattern.column_blocks.size();
  std::vector<Index> perm(6 * n);
  for (std::size_t k = 0; k < n; ++k)
    for (int c = 0; c < 6; ++c) perm[6 * k + c] = 6 * P[k] + c;
  return perm;
}

// The symbolic analysis of H (the cholmod matrix) in that ordering.
detail::FactorPtr analyse(detail::Cholmod& cholmod, const BlockPattern& pattern) {
  cholmod_common* cc = cholmod.common.get();
  std::vector<Index> perm = block_ordering(cholmod, pattern);
  cc->nmethods = 1;
  cc->method[0].ordering = CHOLMOD_GIVEN;
  detail::FactorPtr factor = cholmod.wrap(cholmod_l_analyze_p(cholmod.matrix.get(), perm.data(), nullptr, 0, cc));
  if (!factor) throw std::runtime_error("pose graph: CHOLMOD analysis failed");
  cholmod.factor_flops = cc->fl;
  cholmod.factor_nonzeros = cc->lnz;
  return factor;
}

// H = sum w J^T Omega J and g = sum w J^T Omega e, assembled in place in the values of the CHOLMOD
// matrix: every edge knows beforehand where its three blocks sit. The undamped diagonal is kept
// aside, so a new lambda rewrites only the 6n diagonal entries, not H.
class NormalEquations {
 public:
  NormalEquations(cholmod_sparse* A, const BlockPattern& pattern, const Problem& problem);

  void assemble(const Problem& problem, const std::vector<SE3>& poses, const RobustKernel& kernel);

  /// The values become H + lambda D, D = diag(H) clamped to [1e-6, 1e32] (Marquardt's scaling).
  void damp(double lambda) {
    for (int col = 0; col < dim_; ++col) Ax_[diagonal_index(col)] = diagonal_[col] + lambda * scaling_[col];
  }

  /// y = A x with the values as they stand (H, or H + lambda D after damp()).
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;

  [[nodiscard]] const Eigen::VectorXd& gradient() const { return g_; }
  [[nodiscard]] const Eigen::VectorXd& scaling() const { return scaling_; }

 private:
  // Block column and position among its block rows of an edge's (a, a), (b, b) and off-diagonal
  // blocks; -1 for a held node.
  struct Slots {
    int a, b, aa, bb, off;
  };

  // The diagonal of a column is its last stored entry.
  [[nodiscard]] Index diagonal_index(int col) const { return Ap_[col + 1] - 1; }

  // Adds M to block (R, C), R <= C, the k-th block of column C; only the upper triangle of a
  // diagonal block is stored.
  void add_block(int R, int C, int k, const Matrix6d& M) {
    for (int c = 0; c < 6; ++c) {
      double* col = Ax_ + Ap_[6 * C + c] + 6 * k;
      for (int r = 0; r < (R < C ? 6 : c + 1); ++r) col[r] += M(r, c);
    }
  }

  const Index* Ap_;
  const Index* Ai_;
  double* Ax_;
  int dim_;
  std::vector<Slots> slots_;
  Eigen::VectorXd g_, diagonal_, scaling_;
};

NormalEquations::NormalEquations(cholmod_sparse* A, const BlockPattern& pattern, const Problem& problem)
    : Ap_(static_cast<const Index*>(A->p)),
      Ai_(static_cast<const Index*>(A->i)),
      Ax_(static_cast<double*>(A->x)),
      dim_(static_cast<int>(A->ncol)),
      g_(dim_),
      diagonal_(dim_),
      scaling_(dim_) {
  const auto& columns = pattern.column_blocks;
  const auto last = [&](int C) { return static_cast<int>(columns[C].size()) - 1; };
  slots_.reserve(problem.edges.size());
  for (const auto& de : problem.edges) {
    const int a = problem.var[de.i], b = problem.var[de.j];
    Slots s{a, b, a >= 0 ? last(a) : -1, b >= 0 ? last(b) : -1, -1};
    if (a >= 0 && b >= 0) {
      const auto& rows = columns[std::max(a, b)];
      s.off = static_cast<int>(std::lower_bound(rows.begin(), rows.end(), std::min(a, b)) - rows.begin());
    }
    slots_.push_back(s);
  }
}

void NormalEquations::assemble(const Problem& problem, const std::vector<SE3>& poses, const RobustKernel& kernel) {
  std::fill(Ax_, Ax_ + Ap_[dim_], 0.0);
  g_.setZero();
  for (std::size_t e = 0; e < problem.edges.size(); ++e) {
    const auto& de = problem.edges[e];
    const Slots& s = slots_[e];
    if (s.a < 0 && s.b < 0) continue;
    const auto lin = linearise_edge(poses[de.i], poses[de.j], de.edge->measurement);
    const double chi2 = lin.residual.dot(de.edge->information * lin.residual);
    const Matrix6d W = kernel.weight(chi2, de.edge->robust) * de.edge->information;
    const Vector6d We = W * lin.residual;
    const Matrix6d WJi = W * lin.jacobian_i, WJj = W * lin.jacobian_j;
    if (s.a >= 0) {
      add_block(s.a, s.a, s.aa, lin.jacobian_i.transpose() * WJi);
      g_.segment<6>(6 * s.a) += lin.jacobian_i.transpose() * We;
    }
    if (s.b >= 0) {
      add_block(s.b, s.b, s.bb, lin.jacobian_j.transpose() * WJj);
      g_.segment<6>(6 * s.b) += lin.jacobian_j.transpose() * We;
    }
    if (s.off >= 0) {
      if (s.a < s.b)
        add_block(s.a, s.b, s.off, lin.jacobian_i.transpose() * WJj);
      else
        add_block(s.b, s.a, s.off, lin.jacobian_j.transpose() * WJi);
    }
  }
  for (int col = 0; col < dim_; ++col) {
    diagonal_[col] = Ax_[diagonal_index(col)];
    scaling_[col] = std::clamp(diagonal_[col], 1e-6, 1e32);
  }
}

// Only the upper triangle is stored: an off-diagonal entry (i, j) counts for (j, i) too.
void NormalEquations::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  y.setZero();
  for (int col = 0; col < dim_; ++col) {
    double sum = 0;
    const Index end = Ap_[col + 1] - 1;  // the diagonal, last in the column
    for (Index k = Ap_[col]; k < end; ++k) {
      y[Ai_[k]] += Ax_[k] * x[col];
      sum += Ax_[k] * x[Ai_[k]];
    }
    y[col] += sum + Ax_[end] * x[col];
  }
}

}  // namespace

Optimizer::Optimizer(OptimizerOptions options) : options_(options), cholmod_(std::make_unique<detail::Cholmod>()) {}
Optimizer::~Optimizer() = default;
Optimizer::Optimizer(Optimizer&&) noexcept = default;
Optimizer& Optimizer::operator=(Optimizer&&) noexcept = default;

bool Optimizer::prepare_structure(std::unique_ptr<detail::BlockPattern> pattern) {
  if (pattern_ && *pattern_ == *pattern && cholmod_->factor) return false;
  cholmod_common* cc = cholmod_->common.get();
  cholmod_->factor.reset();
  cholmod_->factorized = false;
  cholmod_->matrix.reset(allocate_matrix(*pattern, /*blocks_only=*/false, cc));
  cholmod_->factor = analyse(*cholmod_, *pattern);
  pattern_ = std::move(pattern);
  ++analyses_;
  return true;
}

namespace {

// Preconditioned conjugate gradients on (H + lambda D) x = b, the preconditioner being the factor
// of an earlier linearisation (cholmod.factor). Near a minimum H changes little from one
// linearisation to the next, so that factor is nearly the inverse, and a few iterations (each a
// product with H and a pair of triangular solves) give the step a refactorisation would. It gives
// up when the matrix proves not positive definite, or when the rate so far would not reach the
// tolerance within max_iterations.
// PCG's stopping test, |b - A x| <= kPcgTolerance |b|: close enough to the exact LM step that the
// cost decrease (and so the stopping test) is the one a factorisation would give.
constexpr double kPcgTolerance = 1e-3;

class Pcg {
 public:
  explicit Pcg(int dim) : x_(dim), r_(dim), z_(dim), p_(dim), q_(dim) {}

  /// Whether |b - A x| <= tolerance |b| was reached; x is then in solution().
  bool solve(const NormalEquations& equations, detail::Cholmod& cholmod, const Eigen::VectorXd& b, double tolerance,
             int max_iterations);
  [[nodiscard]] const Eigen::VectorXd& solution() const { return x_; }
  [[nodiscard]] const Eigen::VectorXd& residual() const { return r_; }  // b - A x
  [[nodiscard]] int iterations() const { return iterations_; }          // of the last solve

 private:
  Eigen::VectorXd x_, r_, z_, p_, q_;
  int iterations_ = 0;
};

bool Pcg::solve(const NormalEquations& equations, detail::Cholmod& cholmod, const Eigen::VectorXd& b, double tolerance,
                int max_iterations) {
  const auto dim = b.size();
  const double b_norm = b.norm();
  x_.setZero();
  r_ = b;
  z_ = Eigen::Map<const Eigen::VectorXd>(cholmod.solve(r_.data()), dim);
  p_ = z_;
  double rz = r_.dot(z_);
  for (iterations_ = 1; iterations_ <= max_iterations; ++iterations_) {
    equations.multiply(p_, q_);
    const double curvature = p_.dot(q_);
    if (!(curvature > 0) || !(rz > 0)) return false;
    const double alpha = rz / curvature;
    x_ += alpha * p_;
    r_ -= alpha * q_;
    const double relative = r_.norm() / b_norm;
    if (relative <= tolerance) return true;
    const double rate = std::pow(relative, 1.0 / iterations_);
    if (iterations_ >= 2 && (rate >= 1.0 || std::log(tolerance) / std::log(rate) > max_iterations)) return false;
    z_ = Eigen::Map<const Eigen::VectorXd>(cholmod.solve(r_.data()), dim);
    const double rz_next = r_.dot(z_);
    p_ = z_ + (rz_next / rz) * p_;
    rz = rz_next;
  }
  return false;
}

// What a linear solve costs, in PCG iterations (4 nnz(L) + 4 nnz(H) flops each, the triangular
// solves and the product with H): a numeric factorisation costs its flop count from the analysis.
struct SolveCosts {
  double factorisation = 0;
  int pcg_limit = 0;  // the most PCG iterations one solve may take; 0: never reuse the factor
};

SolveCosts solve_costs(const detail::Cholmod& cholmod, const OptimizerOptions& options) {
  const double per_iteration = 4.0 * cholmod.factor_nonzeros + 4.0 * static_cast<double>(cholmod.matrix->nzmax);
  SolveCosts costs{cholmod.factor_flops / per_iteration + 1.0, 0};
  if (options.reuse_factorization) costs.pcg_limit = static_cast<int>(std::min(0.5 * costs.factorisation, 30.0));
  return costs;
}

// The LM loop over one linearisation after another (optimizer.hpp). H and g come from
// NormalEquations; the factor, solves and their workspaces from the Cholmod bundle.
class LevenbergMarquardt {
 public:
  LevenbergMarquardt(const OptimizerOptions& options, Problem& problem, NormalEquations& equations,
                     detail::Cholmod& cholmod, OptimizationReport& report)
      : options_(options),
        kernel_{options.pose_graph.cauchy_delta},
        problem_(problem),
        equations_(equations),
        cholmod_(cholmod),
        report_(report),
        costs_(solve_costs(cholmod, options)),
        candidate_(problem.poses),
        pcg_(static_cast<int>(equations.gradient().size())),
        rhs_(equations.gradient().size()),
        cost_(report.initial_cost),
        factor_usable_(cholmod.factorized) {}

  /// Runs to a stop, or until `deadline`; returns (stop reason, converged).
  std::pair<std::string, bool> run(std::chrono::steady_clock::time_point deadline);

 private:
  enum class Outcome { kAccepted, kRejected, kSmallStep };

  Outcome iterate(IterationRecord& record);
  bool pcg_worthwhile() const;
  Outcome try_step(const Eigen::VectorXd& step, const Eigen::VectorXd* residual);
  void raise_lambda() {
    lambda_ *= nu_;
    nu_ *= 2.0;
  }

  const OptimizerOptions& options_;
  const RobustKernel kernel_;
  Problem& problem_;
  NormalEquations& equations_;
  detail::Cholmod& cholmod_;
  OptimizationReport& report_;
  const SolveCosts costs_;
  std::vector<SE3> candidate_;
  Pcg pcg_;
  Eigen::VectorXd rhs_;
  double cost_;
  double lambda_ = 0;
  double nu_ = 2.0;
  double decrease_ = 0;  // of the last accepted step
  bool factor_usable_;   // a factorisation of this structure is at hand, perhaps from an earlier call
  // Solve work since the last factorisation (in PCG iterations, the factorisation included), the
  // iterations it served, and the work of the last iteration.
  double work_since_factor_ = 0;
  int iterations_since_factor_ = 0;
  double last_work_ = 0;
};

// Puts the step on the poses and evaluates; accepts it when the cost goes down, updating lambda
// by the gain ratio (actual over predicted decrease, the model being g.d + 1/2 d^T H d). residual:
// PCG's r = -g - (H + lambda D) d, or nullptr for a direct solve (r = 0).
LevenbergMarquardt::Outcome LevenbergMarquardt::try_step(const Eigen::VectorXd& step, const Eigen::VectorXd* residual) {
  if (!step.allFinite()) return Outcome::kRejected;
  if (step.norm() < options_.step_tolerance) return Outcome::kSmallStep;
  const auto& poses = problem_.poses;
  for (std::size_t k = 0; k < poses.size(); ++k)
    candidate_[k] = problem_.var[k] < 0 ? poses[k] : retract(poses[k], step.segment<6>(6 * problem_.var[k]));
  const double new_cost = problem_cost(problem_, candidate_, kernel_);
  if (!(std::isfinite(new_cost) && new_cost < cost_)) return Outcome::kRejected;
  // With (H + lambda D) d = -g - r: -g.d - 1/2 d^T H d = 1/2 d.(lambda D d - g + r).
  const Eigen::VectorXd& g = equations_.gradient();
  const double model = step.dot(lambda_ * equations_.scaling().cwiseProduct(step) - g);
  const double predicted = 0.5 * (residual != nullptr ? model + step.dot(*residual) : model);
  const double gain = predicted > 0 ? (cost_ - new_cost) / predicted : 0.0;
  lambda_ *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * gain - 1.0, 3));
  nu_ = 2.0;
  decrease_ = cost_ - new_cost;
  problem_.poses.swap(candidate_);
  cost_ = new_cost;
  return Outcome::kAccepted;
}

// While steps still lower the cost by more than this fraction, H changes too much between
// linearisations for an earlier factor to precondition it (PCG would not converge: wasted solves).
constexpr double kPcgAfterDecrease = 0.1;

// PCG needs more iterations the further the poses have moved since the factorisation. Once the
// last iteration's solve work exceeds the average per iteration since the factorisation (that
// included), the average only grows: refactorising is then cheaper in the long run.
bool LevenbergMarquardt::pcg_worthwhile() const {
  return factor_usable_ && costs_.pcg_limit > 0 && decrease_ < kPcgAfterDecrease * (cost_ + decrease_) &&
         last_work_ * iterations_since_factor_ <= work_since_factor_;
}

// One linearisation: damp H, find the step, raise lambda until the cost goes down. The step comes
// from PCG on the factor at hand while that is worthwhile and converges, else from a fresh
// factorisation. Both solve the damped system (PCG to a relative residual of 1e-3), so the
// stopping test means the same for both.
LevenbergMarquardt::Outcome LevenbergMarquardt::iterate(IterationRecord& record) {
  rhs_ = -equations_.gradient();
  bool try_pcg = pcg_worthwhile();
  double work = 0;
  Outcome outcome = Outcome::kRejected;
  while (lambda_ <= 1e32 && outcome == Outcome::kRejected) {
    equations_.damp(lambda_);  // H itself stays: a rejected step changes only the diagonal
    const bool converged = try_pcg && pcg_.solve(equations_, cholmod_, rhs_, kPcgTolerance, costs_.pcg_limit);
    work += try_pcg ? pcg_.iterations() : 0;
    if (converged) {
      outcome = try_step(pcg_.solution(), &pcg_.residual());
    } else {
      try_pcg = false;
      ++record.trials;
      ++report_.factorizations;
      work = costs_.factorisation;
      factor_usable_ = cholmod_.factorize();
      if (factor_usable_)
        outcome = try_step(Eigen::Map<const Eigen::VectorXd>(cholmod_.solve(rhs_.data()), rhs_.size()), nullptr);
    }
    if (outcome == Outcome::kRejected) raise_lambda();
  }
  record.reused_factorization = record.trials == 0;
  if (record.trials > 0) work_since_factor_ = iterations_since_factor_ = 0;
  work_since_factor_ += work;
  last_work_ = work;
  ++iterations_since_factor_;
  return outcome;
}

std::pair<std::string, bool> LevenbergMarquardt::run(std::chrono::steady_clock::time_point deadline) {
  lambda_ = options_.initial_lambda;
  for (int it = 0; it < options_.pose_graph.max_iterations; ++it) {
    if (cost_ == 0.0) return {"zero cost", true};
    if (std::chrono::steady_clock::now() >= deadline) return {kTimeLimit, false};
    equations_.assemble(problem_, problem_.poses, kernel_);
    IterationRecord record;
    const Outcome outcome = iterate(record);
    record.cost = cost_;
    record.lambda = lambda_;
    report_.log.push_back(record);
    report_.iterations = it + 1;
    report_.final_cost = cost_;
    if (outcome == Outcome::kSmallStep) return {"step below tolerance", true};
    if (outcome == Outcome::kRejected) return {"lambda too large: no step lowers the cost", false};
    if (decrease_ <= options_.relative_decrease * (cost_ + decrease_))
      return {"relative cost decrease below tolerance", true};
  }
  return {"maximum iterations", false};
}

}  // namespace

// optimize()'s deadline: max_seconds after its start, the far future when that is unbounded.
std::chrono::steady_clock::time_point Optimizer::deadline(std::chrono::steady_clock::time_point start) const {
  const double budget = options_.max_seconds;
  if (!(budget < 1e9)) return std::chrono::steady_clock::time_point::max();  // unbounded (or NaN)
  return start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                     std::chrono::duration<double>(std::max(budget, 0.0)));
}

OptimizationReport Optimizer::optimize(PoseGraph& graph) {
  const auto start = std::chrono::steady_clock::now();
  Problem problem = make_problem(graph);
  OptimizationReport report;
  report.initial_cost = report.final_cost =
      problem_cost(problem, problem.poses, RobustKernel{options_.pose_graph.cauchy_delta});
  const auto finish = [&](std::string reason, bool converged) {
    for (std::size_t k = 0; const auto& kv : graph.nodes()) graph.set_pose(kv.first, problem.poses[k++]);
    report.stop_reason = std::move(reason);
    report.converged = converged;
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
  };
  if (std::none_of(problem.var.begin(), problem.var.end(), [](int v) { return v >= 0; }))
    return finish("no free nodes", true);

  report.reanalysed = prepare_structure(make_pattern(graph, problem));
  NormalEquations equations(cholmod_->matrix.get(), *pattern_, problem);
  auto [reason, converged] = LevenbergMarquardt(options_, problem, equations, *cholmod_, report).run(deadline(start));
  return finish(std::move(reason), converged);
}

OptimizationReport optimize(PoseGraph& graph, const OptimizerOptions& options) {
  return Optimizer(options).optimize(graph);
}

}  // namespace cvo::posegraph
