#include "libcvo/posegraph/marginals.hpp"

#include <algorithm>
#include <stdexcept>
#include <unordered_map>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "libcvo/posegraph/cost.hpp"
#include "libcvo/posegraph/residual.hpp"

namespace cvo::posegraph {
namespace {

constexpr int kBatch = 64;  // requested nodes per multi-column solve (memory: 6 kBatch columns of H's size)

// Each free node's variable block (the optimiser's gauge: fixed nodes held, else the first).
std::unordered_map<NodeId, int> variables(const PoseGraph& graph) {
  const bool any_fixed =
      std::any_of(graph.nodes().begin(), graph.nodes().end(), [](const auto& kv) { return kv.second.fixed; });
  std::unordered_map<NodeId, int> var;
  bool first = true;
  for (const auto& [id, node] : graph.nodes()) {
    const bool held = node.fixed || (!any_fixed && first);
    first = false;
    if (!held) var.emplace(id, static_cast<int>(var.size()));
  }
  return var;
}

void add_block(std::vector<Eigen::Triplet<double>>& t, int r, int c, const core::Matrix6d& block) {
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) t.emplace_back(6 * r + i, 6 * c + j, block(i, j));
}

Eigen::SparseMatrix<double> information(const PoseGraph& graph, const std::unordered_map<NodeId, int>& var,
                                        const RobustKernel& kernel) {
  std::vector<Eigen::Triplet<double>> t;
  for (const Edge& e : graph.edges()) {
    const auto a = var.find(e.from), b = var.find(e.to);
    if (a == var.end() && b == var.end()) continue;
    const auto lin = linearise_edge(graph.node(e.from).pose, graph.node(e.to).pose, e.measurement);
    const double chi2 = lin.residual.dot(e.information * lin.residual);
    const core::Matrix6d W = kernel.weight(chi2, e.robust) * e.information;
    if (a != var.end()) add_block(t, a->second, a->second, lin.jacobian_i.transpose() * W * lin.jacobian_i);
    if (b != var.end()) add_block(t, b->second, b->second, lin.jacobian_j.transpose() * W * lin.jacobian_j);
    if (a != var.end() && b != var.end()) {
      const core::Matrix6d off = lin.jacobian_i.transpose() * W * lin.jacobian_j;
      add_block(t, a->second, b->second, off);
      add_block(t, b->second, a->second, off.transpose());
    }
  }
  const auto n = static_cast<Eigen::Index>(6 * var.size());
  Eigen::SparseMatrix<double> H(n, n);
  H.setFromTriplets(t.begin(), t.end());
  return H;
}

}  // namespace

std::map<NodeId, core::Matrix6d> marginal_covariances(const PoseGraph& graph, const std::vector<NodeId>& nodes,
                                                      const OptimizerOptions& options) {
  for (const NodeId id : nodes)
    if (!graph.contains(id)) throw std::out_of_range("marginal_covariances: no node " + std::to_string(id));
  const auto var = variables(graph);
  std::map<NodeId, core::Matrix6d> out;
  std::vector<NodeId> free;
  for (const NodeId id : nodes) {
    if (var.contains(id))
      free.push_back(id);
    else
      out[id] = core::Matrix6d::Zero();
  }
  if (free.empty()) return out;
  const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(
      information(graph, var, RobustKernel{options.pose_graph.cauchy_delta}));
  if (llt.info() != Eigen::Success)
    throw std::runtime_error("marginal_covariances: the information is not positive definite");
  const auto n = static_cast<Eigen::Index>(6 * var.size());
  for (std::size_t begin = 0; begin < free.size(); begin += kBatch) {
    const std::size_t count = std::min<std::size_t>(kBatch, free.size() - begin);
    Eigen::MatrixXd E = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(6 * count));
    for (std::size_t k = 0; k < count; ++k)
      E.block<6, 6>(6 * var.at(free[begin + k]), static_cast<Eigen::Index>(6 * k)).setIdentity();
    const Eigen::MatrixXd X = llt.solve(E);
    for (std::size_t k = 0; k < count; ++k) {
      const core::Matrix6d block = X.block<6, 6>(6 * var.at(free[begin + k]), static_cast<Eigen::Index>(6 * k));
      out[free[begin + k]] = 0.5 * (block + block.transpose());
    }
  }
  return out;
}

}  // namespace cvo::posegraph
