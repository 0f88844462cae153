#include "libcvo/lcm/local_graph_conversion.hpp"

#include <algorithm>
#include <cmath>

#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {
namespace {
std::nullopt_t fail(std::string* error, const std::string& what) {
  if (error != nullptr) *error = "cvo_lcm.local_graph_t: " + what;
  return std::nullopt;
}
}  // namespace

cvo_lcm::local_graph_t to_message(const odometry::LocalGraph& graph, std::int64_t session, std::int64_t keyframe_id,
                                  std::int64_t utime) {
  cvo_lcm::local_graph_t m{};
  m.version = cvo_lcm::local_graph_t::SCHEMA_VERSION;
  m.session = session;
  m.keyframe_id = keyframe_id;
  m.utime = utime;
  for (const auto& n : graph.nodes())
    m.nodes.push_back({static_cast<std::int64_t>(n.frame_index), to_utime(n.timestamp), to_message(n.pose)});
  for (const auto& e : graph.edges()) {
    cvo_lcm::graph_edge_t edge{};
    edge.from = static_cast<std::int64_t>(e.from);
    edge.to = static_cast<std::int64_t>(e.to);
    edge.measurement = to_message(e.measurement);
    matrix6_to_message(e.information, edge.information);
    m.edges.push_back(edge);
  }
  m.num_nodes = static_cast<std::int32_t>(m.nodes.size());
  m.num_edges = static_cast<std::int32_t>(m.edges.size());
  return m;
}

std::optional<odometry::LocalGraph> from_message(const cvo_lcm::local_graph_t& m, std::string* error) {
  if (m.version != cvo_lcm::local_graph_t::SCHEMA_VERSION) return fail(error, "schema version " + std::to_string(m.version));
  if (m.num_nodes < 1) return fail(error, "no nodes (a local graph has at least its keyframe)");
  // Capacity num_nodes: add_edge() then refuses a third edge per node, as the tracker never makes one.
  odometry::LocalGraph graph(static_cast<std::size_t>(m.num_nodes));
  std::string why;
  for (const auto& n : m.nodes) {
    const auto pose = from_message(n.pose, &why);
    if (!pose) return fail(error, "node " + std::to_string(n.frame_index) + ": " + why);
    if (n.frame_index < 0) return fail(error, "negative frame index " + std::to_string(n.frame_index));
    graph.add_node({static_cast<std::uint64_t>(n.frame_index), from_utime(n.utime), *pose});
  }
  const auto is_node = [&](std::int64_t index) {
    return std::any_of(graph.nodes().begin(), graph.nodes().end(),
                       [&](const odometry::LocalGraphNode& n) { return static_cast<std::int64_t>(n.frame_index) == index; });
  };
  for (const auto& e : m.edges) {
    if (!is_node(e.from) || !is_node(e.to))
      return fail(error, "edge " + std::to_string(e.from) + "->" + std::to_string(e.to) + " names a frame not in the graph");
    const auto measurement = from_message(e.measurement, &why);
    if (!measurement) return fail(error, "edge " + std::to_string(e.from) + "->" + std::to_string(e.to) + ": " + why);
    const core::Matrix6d information = matrix6_from_message(e.information);
    if (!information.allFinite()) return fail(error, "edge " + std::to_string(e.from) + "->" + std::to_string(e.to) + ": information is not finite");
    if (!graph.add_edge({static_cast<std::uint64_t>(e.from), static_cast<std::uint64_t>(e.to), *measurement, information}))
      return fail(error, "more than two edges per node");
  }
  return graph;
}

}  // namespace cvo::lcm
