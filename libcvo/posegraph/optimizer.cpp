#include "libcvo/posegraph/optimizer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

#include "libcvo/posegraph/cholmod_handles.hpp"
#include "libcvo/posegraph/residual.hpp"

namespace cvo::posegraph {

// The sparsity of H: which 6x6 blocks exist. Block column C holds block rows column_blocks[C]
// (sorted, all <= C, the last one C itself); column 6C + c of the upper triangle then holds
// 6 rows for every off-diagonal block and c + 1 rows of the diagonal block.
struct Optimizer::Pattern {
  std::vector<NodeId> free_ids;
  std::vector<std::vector<int>> column_blocks;

  bool operator==(const Pattern&) const = default;
};

namespace {

using core::Matrix6d;
using core::SE3;
using core::Vector6d;

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
  const bool any_fixed = std::any_of(graph.nodes().begin(), graph.nodes().end(),
                                     [](const auto& kv) { return kv.second.fixed; });
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

}  // namespace

Optimizer::Optimizer(OptimizerOptions options)
    : options_(options), cholmod_(std::make_unique<detail::Cholmod>()) {}
Optimizer::~Optimizer() = default;
Optimizer::Optimizer(Optimizer&&) noexcept = default;
Optimizer& Optimizer::operator=(Optimizer&&) noexcept = default;

OptimizationReport Optimizer::optimize(PoseGraph& graph) {
  const auto start = std::chrono::steady_clock::now();
  const RobustKernel kernel{options_.cauchy_delta};
  Problem problem = make_problem(graph);
  std::vector<SE3>& poses = problem.poses;

  OptimizationReport report;
  report.initial_cost = report.final_cost = problem_cost(problem, poses, kernel);
  const auto finish = [&](std::string reason, bool converged) {
    for (std::size_t k = 0; const auto& kv : graph.nodes()) graph.set_pose(kv.first, poses[k++]);
    report.stop_reason = std::move(reason);
    report.converged = converged;
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
  };

  // --- Structure: blocks of H, and a new symbolic analysis only when they changed.
  auto pattern = std::make_unique<Pattern>();
  for (std::size_t k = 0; const auto& kv : graph.nodes())
    if (problem.var[k++] >= 0) pattern->free_ids.push_back(kv.first);
  const int n = static_cast<int>(pattern->free_ids.size());
  if (n == 0) return finish("no free nodes", true);
  pattern->column_blocks.resize(n);
  for (const auto& de : problem.edges) {
    const int a = problem.var[de.i], b = problem.var[de.j];
    if (a >= 0 && b >= 0 && a != b) pattern->column_blocks[std::max(a, b)].push_back(std::min(a, b));
  }
  for (int c = 0; c < n; ++c) {
    auto& rows = pattern->column_blocks[c];
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    rows.push_back(c);
  }
  cholmod_common* cc = cholmod_->common.get();
  if (!pattern_ || !(*pattern_ == *pattern) || !cholmod_->factor) {
    std::size_t nnz = 0;
    for (const auto& rows : pattern->column_blocks) nnz += 36 * (rows.size() - 1) + 21;
    const auto dim = static_cast<std::size_t>(6 * n);
    cholmod_->factor.reset();
    cholmod_->matrix.reset(cholmod_l_allocate_sparse(dim, dim, nnz, /*sorted=*/1, /*packed=*/1,
                                                    /*stype=upper*/ 1, CHOLMOD_REAL, cc));
    if (!cholmod_->matrix) throw std::runtime_error("pose graph: CHOLMOD could not allocate H");
    auto* Ap = static_cast<SuiteSparse_long*>(cholmod_->matrix->p);
    auto* Ai = static_cast<SuiteSparse_long*>(cholmod_->matrix->i);
    SuiteSparse_long pos = 0;
    for (int C = 0; C < n; ++C)
      for (int c = 0; c < 6; ++c) {
        Ap[6 * C + c] = pos;
        for (const int R : pattern->column_blocks[C])
          for (int r = 0; r < (R < C ? 6 : c + 1); ++r) Ai[pos++] = 6 * R + r;
      }
    Ap[6 * n] = pos;
    cholmod_->factor.reset(cholmod_l_analyze(cholmod_->matrix.get(), cc));
    if (!cholmod_->factor) throw std::runtime_error("pose graph: CHOLMOD analysis failed");
    pattern_ = std::move(pattern);
    ++analyses_;
    report.reanalysed = true;
  }
  cholmod_sparse* A = cholmod_->matrix.get();
  const auto* Ap = static_cast<const SuiteSparse_long*>(A->p);
  auto* Ax = static_cast<double*>(A->x);
  const std::size_t nnz = static_cast<std::size_t>(Ap[6 * n]);
  const auto& column_blocks = pattern_->column_blocks;

  // Where each edge's off-diagonal block sits: its index among its column's block rows.
  std::vector<int> off_slot(problem.edges.size(), -1);
  for (std::size_t e = 0; e < problem.edges.size(); ++e) {
    const int a = problem.var[problem.edges[e].i], b = problem.var[problem.edges[e].j];
    if (a < 0 || b < 0) continue;
    const auto& rows = column_blocks[std::max(a, b)];
    off_slot[e] = static_cast<int>(std::lower_bound(rows.begin(), rows.end(), std::min(a, b)) - rows.begin());
  }

  std::vector<double> H(nnz);
  Eigen::VectorXd g(6 * n);
  // Adds M to block (R, C), R <= C, the k-th block of column C; only the upper triangle of a
  // diagonal block is stored.
  const auto add_block = [&](int R, int C, int k, const Matrix6d& M) {
    for (int c = 0; c < 6; ++c) {
      double* col = H.data() + Ap[6 * C + c] + 6 * k;
      for (int r = 0; r < (R < C ? 6 : c + 1); ++r) col[r] += M(r, c);
    }
  };
  const auto linearise = [&] {
    std::fill(H.begin(), H.end(), 0.0);
    g.setZero();
    for (std::size_t e = 0; e < problem.edges.size(); ++e) {
      const auto& de = problem.edges[e];
      const int a = problem.var[de.i], b = problem.var[de.j];
      if (a < 0 && b < 0) continue;
      const auto lin = linearise_edge(poses[de.i], poses[de.j], de.edge->measurement);
      const double chi2 = lin.residual.dot(de.edge->information * lin.residual);
      const Matrix6d W = kernel.weight(chi2, de.edge->robust) * de.edge->information;
      const Vector6d We = W * lin.residual;
      if (a >= 0) {
        add_block(a, a, static_cast<int>(column_blocks[a].size()) - 1, lin.jacobian_i.transpose() * W * lin.jacobian_i);
        g.segment<6>(6 * a) += lin.jacobian_i.transpose() * We;
      }
      if (b >= 0) {
        add_block(b, b, static_cast<int>(column_blocks[b].size()) - 1, lin.jacobian_j.transpose() * W * lin.jacobian_j);
        g.segment<6>(6 * b) += lin.jacobian_j.transpose() * We;
      }
      if (a >= 0 && b >= 0) {
        if (a < b) add_block(a, b, off_slot[e], lin.jacobian_i.transpose() * W * lin.jacobian_j);
        else add_block(b, a, off_slot[e], lin.jacobian_j.transpose() * W * lin.jacobian_i);
      }
    }
  };

  // The diagonal of column col is its last stored entry.
  const auto diagonal_index = [&](int col) { return static_cast<std::size_t>(Ap[col + 1] - 1); };

  auto rhs = cholmod_->wrap(cholmod_l_zeros(6 * n, 1, CHOLMOD_REAL, cc));
  if (!rhs) throw std::runtime_error("pose graph: CHOLMOD could not allocate the right-hand side");
  double lambda = options_.initial_lambda;
  double nu = 2.0;
  double cost = report.initial_cost;
  std::vector<SE3> candidate = poses;

  for (int it = 0; it < options_.max_iterations; ++it) {
    if (cost == 0.0) return finish("zero cost", true);
    linearise();
    Eigen::Map<Eigen::VectorXd>(static_cast<double*>(rhs->x), 6 * n) = -g;
    IterationRecord record;
    bool accepted = false;
    bool small_step = false;
    while (!accepted) {
      if (lambda > 1e32) {
        report.log.push_back({cost, lambda, record.trials});
        report.iterations = it + 1;
        return finish("lambda too large: no step lowers the cost", false);
      }
      ++record.trials;
      std::copy(H.begin(), H.end(), Ax);
      Eigen::VectorXd D(6 * n);
      for (int col = 0; col < 6 * n; ++col) {
        D[col] = std::clamp(H[diagonal_index(col)], 1e-6, 1e32);
        Ax[diagonal_index(col)] += lambda * D[col];
      }
      if (!cholmod_l_factorize(A, cholmod_->factor.get(), cc) || cc->status == CHOLMOD_NOT_POSDEF) {
        lambda *= nu;
        nu *= 2.0;
        continue;
      }
      auto solution = cholmod_->wrap(cholmod_l_solve(CHOLMOD_A, cholmod_->factor.get(), rhs.get(), cc));
      if (!solution) throw std::runtime_error("pose graph: CHOLMOD solve failed");
      const Eigen::Map<const Eigen::VectorXd> delta(static_cast<const double*>(solution->x), 6 * n);
      if (!delta.allFinite()) {
        lambda *= nu;
        nu *= 2.0;
        continue;
      }
      if (delta.norm() < options_.step_tolerance) {
        small_step = true;
        break;
      }
      for (std::size_t k = 0; k < poses.size(); ++k)
        candidate[k] = problem.var[k] < 0 ? poses[k] : retract(poses[k], delta.segment<6>(6 * problem.var[k]));
      const double new_cost = problem_cost(problem, candidate, kernel);
      const double predicted = 0.5 * delta.dot(lambda * D.cwiseProduct(delta) - g);
      const double gain = predicted > 0 ? (cost - new_cost) / predicted : -1.0;
      if (std::isfinite(new_cost) && new_cost < cost) {
        accepted = true;
        const double decrease = cost - new_cost;
        poses.swap(candidate);
        cost = new_cost;
        lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * std::max(gain, 0.0) - 1.0, 3));
        nu = 2.0;
        record.cost = cost;
        record.lambda = lambda;
        report.log.push_back(record);
        report.iterations = it + 1;
        report.final_cost = cost;
        if (decrease <= options_.relative_decrease * (cost + decrease))
          return finish("relative cost decrease below tolerance", true);
      } else {
        lambda *= nu;
        nu *= 2.0;
      }
    }
    if (small_step) {
      record.cost = cost;
      record.lambda = lambda;
      report.log.push_back(record);
      report.iterations = it + 1;
      return finish("step below tolerance", true);
    }
  }
  return finish("maximum iterations", false);
}

OptimizationReport optimize(PoseGraph& graph, const OptimizerOptions& options) {
  return Optimizer(options).optimize(graph);
}

}  // namespace cvo::posegraph
