#include "daemon/trackerd/killed_graph.hpp"

#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/local_graph_t.hpp"
#include "libcvo/lcm/decode.hpp"

namespace cvo::daemon::trackerd {

std::optional<std::vector<std::uint8_t>> graph_of_killed_keyframe(std::span<const std::uint8_t> keyframe,
                                                                  std::int64_t utime) {
  const auto k = lcm::decode<cvo_lcm::keyframe_t>(keyframe.data(), static_cast<int>(keyframe.size()), nullptr);
  if (!k) return std::nullopt;
  cvo_lcm::local_graph_t g{};
  g.version = cvo_lcm::local_graph_t::SCHEMA_VERSION;
  g.session = k->session;
  g.keyframe_id = k->id;
  g.utime = utime;
  g.nodes = {{k->frame_index, k->utime, k->pose}};  // the keyframe node, as the tracker writes it
  g.num_nodes = 1;
  g.num_edges = 0;
  g.robot = k->robot;
  return lcm::encode(g);
}

}  // namespace cvo::daemon::trackerd
