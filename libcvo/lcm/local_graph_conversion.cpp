#include "libcvo/lcm/local_graph_conversion.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "libcvo/core/information.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {
namespace {

std::nullopt_t fail(std::string* error, const std::string& what) {
  if (error != nullptr) *error = "cvo_lcm.local_graph_t: " + what;
  return std::nullopt;
}

// Why a part of the message cannot be used, and which kind of refusal that is.
struct Refusal {
  ContentFailure kind;
  std::string what;
};

bool is_node(const odometry::LocalGraph& graph, std::int64_t index) {
  return std::any_of(graph.nodes().begin(), graph.nodes().end(), [&](const odometry::LocalGraphNode& n) {
    return static_cast<std::int64_t>(n.frame_index) == index;
  });
}

std::optional<Refusal> add_node(const cvo_lcm::local_graph_node_t& n, odometry::LocalGraph& graph) {
  const std::string name = "node " + std::to_string(n.frame_index);
  std::string why;
  const auto pose = from_message(n.pose, &why);
  if (!pose)
    return Refusal{is_finite(n.pose) ? ContentFailure::kContent : ContentFailure::kNotFinite, name + ": " + why};
  if (n.frame_index < 0)
    return Refusal{ContentFailure::kContent, "negative frame index " + std::to_string(n.frame_index)};
  graph.add_node({static_cast<std::uint64_t>(n.frame_index), from_utime(n.utime), *pose});
  return std::nullopt;
}

// The information is checked as the back end will use it (core/information.hpp), so a graph
// that would make its cost unbounded below is refused here, at the door, naming the edge.
std::optional<Refusal> add_edge(const cvo_lcm::graph_edge_t& e, odometry::LocalGraph& graph) {
  const std::string name = "edge " + std::to_string(e.from) + "->" + std::to_string(e.to);
  if (!is_node(graph, e.from) || !is_node(graph, e.to))
    return Refusal{ContentFailure::kContent, name + " names a frame not in the graph"};
  std::string why;
  const auto measurement = from_message(e.measurement, &why);
  if (!measurement)
    return Refusal{is_finite(e.measurement) ? ContentFailure::kContent : ContentFailure::kNotFinite, name + ": " + why};
  const core::Matrix6d information = matrix6_from_message(e.information);
  if (const auto check = core::check_information(information); !check.ok())
    return Refusal{
        check.defect == core::InformationDefect::kNotFinite ? ContentFailure::kNotFinite : ContentFailure::kInformation,
        name + ": " + check.why()};
  if (!graph.add_edge(
          {static_cast<std::uint64_t>(e.from), static_cast<std::uint64_t>(e.to), *measurement, information}))
    return Refusal{ContentFailure::kContent, "more than two edges per node"};
  return std::nullopt;
}

}  // namespace

cvo_lcm::local_graph_t to_message(const odometry::LocalGraph& graph, std::int64_t session, std::int64_t keyframe_id,
                                  std::int64_t utime, std::string_view robot) {
  cvo_lcm::local_graph_t m{};
  m.robot = robot;
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

std::optional<odometry::LocalGraph> from_message(const cvo_lcm::local_graph_t& m, std::string* error,
                                                 ContentFailure* failure) {
  const auto refuse = [&](const Refusal& r) {
    if (failure != nullptr) *failure = r.kind;
    return fail(error, r.what);
  };
  if (m.version != cvo_lcm::local_graph_t::SCHEMA_VERSION)
    return refuse({ContentFailure::kContent, "schema version " + std::to_string(m.version)});
  if (auto why = core::robot_name_error(m.robot); !why.empty()) return refuse({ContentFailure::kContent, why});
  if (m.num_nodes < 1) return refuse({ContentFailure::kContent, "no nodes (a local graph has at least its keyframe)"});
  // Capacity num_nodes: add_edge() then refuses a third edge per node, as the tracker never makes one.
  odometry::LocalGraph graph(static_cast<std::size_t>(m.num_nodes));
  for (const auto& n : m.nodes)
    if (const auto refusal = add_node(n, graph)) return refuse(*refusal);
  for (const auto& e : m.edges)
    if (const auto refusal = add_edge(e, graph)) return refuse(*refusal);
  return graph;
}

}  // namespace cvo::lcm
