#include "libcvo/posegraph/arrivals.hpp"

#include <algorithm>
#include <map>

namespace cvo::posegraph {

std::vector<Arrival> arrivals(const PoseGraph& graph) {
  std::vector<Arrival> result;
  std::map<NodeId, std::size_t> slot;
  for (const auto& [id, node] : graph.nodes()) {
    slot.emplace(id, result.size());
    result.push_back({id, node.fixed, {}});
  }
  for (const Edge& e : graph.edges()) result[slot.at(std::max(e.from, e.to))].edges.push_back(e);
  return result;
}

core::SE3 arrival_guess(const IncrementalOptimizer& optimizer, const Arrival& arrival, const core::SE3& fallback) {
  for (const Edge& e : arrival.edges) {
    if (e.to == arrival.node && optimizer.contains(e.from)) return optimizer.pose(e.from) * e.measurement;
    if (e.from == arrival.node && optimizer.contains(e.to)) return optimizer.pose(e.to) * e.measurement.inverse();
  }
  return fallback;
}

void add_arrival(IncrementalOptimizer& optimizer, const Arrival& arrival, const core::SE3& fallback) {
  optimizer.add_node(arrival.node, arrival_guess(optimizer, arrival, fallback), arrival.fixed);
  for (const Edge& e : arrival.edges) optimizer.add_edge(e);
}

}  // namespace cvo::posegraph
