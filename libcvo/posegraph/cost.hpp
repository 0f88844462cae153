#pragma once
// The objective: F = 1/2 sum_edges rho(s), s = e^T Omega e (the edge's chi^2).
//   plain edges:  rho(s) = s
//   robust edges: rho(s) = delta^2 log(1 + s / delta^2)   (Cauchy; Ceres' CauchyLoss(delta))
// The optimiser solves it by iteratively re-weighted least squares: at each linearisation an edge
// gets weight w = rho'(s) = 1 / (1 + s / delta^2), and its Gauss-Newton block is w J^T Omega J.
#include <cmath>

#include "libcvo/core/parameters.hpp"
#include "libcvo/posegraph/pose_graph.hpp"

namespace cvo::posegraph {

struct RobustKernel {
  double delta = core::PoseGraphParameters{}.cauchy_delta;

  [[nodiscard]] double rho(double s, bool robust) const {
    return robust ? delta * delta * std::log1p(s / (delta * delta)) : s;
  }
  [[nodiscard]] double weight(double s, bool robust) const { return robust ? 1.0 / (1.0 + s / (delta * delta)) : 1.0; }
};

/// chi^2 of one edge, e^T Omega e, at the graph's current poses.
double edge_chi2(const PoseGraph& graph, const Edge& edge);

/// F = 1/2 sum rho(chi^2) at the graph's current poses.
double cost(const PoseGraph& graph, const RobustKernel& kernel = {});

}  // namespace cvo::posegraph
