#pragma once
// odometry::LocalGraph <-> cvo_lcm::local_graph_t (channel CVO_LOCAL_GRAPH).
#include <cstdint>
#include <optional>
#include <string>

#include "cvo_lcm/local_graph_t.hpp"
#include "libcvo/odometry/local_graph.hpp"

namespace cvo::lcm {

/// The graph of keyframe (session, keyframe_id), closed at `utime`.
cvo_lcm::local_graph_t to_message(const odometry::LocalGraph& graph, std::int64_t session, std::int64_t keyframe_id,
                                  std::int64_t utime);

/// Fails on another schema version, an empty graph, a bad pose or information matrix (not
/// finite), or an edge naming a frame that is not a node of the graph.
std::optional<odometry::LocalGraph> from_message(const cvo_lcm::local_graph_t& message, std::string* error);

}  // namespace cvo::lcm
