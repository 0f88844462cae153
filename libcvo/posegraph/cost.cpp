#include "libcvo/posegraph/cost.hpp"

#include "libcvo/posegraph/residual.hpp"

namespace cvo::posegraph {

double edge_chi2(const PoseGraph& graph, const Edge& edge) {
  const core::Vector6d e = edge_residual(graph.node(edge.from).pose, graph.node(edge.to).pose, edge.measurement);
  return e.dot(edge.information * e);
}

double cost(const PoseGraph& graph, const RobustKernel& kernel) {
  double sum = 0;
  for (const Edge& edge : graph.edges()) sum += kernel.rho(edge_chi2(graph, edge), edge.robust);
  return 0.5 * sum;
}

}  // namespace cvo::posegraph
