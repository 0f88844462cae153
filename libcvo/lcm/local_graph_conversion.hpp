#pragma once
// odometry::LocalGraph <-> cvo_lcm::local_graph_t (channel CVO_LOCAL_GRAPH).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "cvo_lcm/local_graph_t.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/odometry/local_graph.hpp"

namespace cvo::lcm {

/// The graph of keyframe (session, keyframe_id) of `robot`, closed at `utime`.
cvo_lcm::local_graph_t to_message(const odometry::LocalGraph& graph, std::int64_t session, std::int64_t keyframe_id,
                                  std::int64_t utime, std::string_view robot);

/// Fails on another schema version, a robot name that is none (core::is_robot_name), an empty graph, a bad pose, an
/// edge naming a frame that is not a node of the graph, or an information matrix that core::check_information refuses
/// (not finite, not symmetric, not positive semi-definite), with a message naming the node or edge. *failure (when
/// given) says which kind: kNotFinite for a NaN or infinite pose or information, kInformation for a finite information
/// matrix that is not symmetric positive semi-definite, kContent for the rest.
std::optional<odometry::LocalGraph> from_message(const cvo_lcm::local_graph_t& message, std::string* error,
                                                 ContentFailure* failure = nullptr);

}  // namespace cvo::lcm
