#pragma once
// One message of each cvo_lcm type with every field set to a distinct, non-default value and every
// array non-empty, so that a round trip or a truncation exercises the whole encoding.
#include <algorithm>
#include <cstdint>

#include "cvo_lcm/grid_t.hpp"
#include "cvo_lcm/keyframe_chunk_t.hpp"
#include "cvo_lcm/keyframe_request_t.hpp"
#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/local_graph_t.hpp"
#include "cvo_lcm/map_correction_t.hpp"
#include "cvo_lcm/map_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "cvo_lcm/rgbd_frame_t.hpp"
#include "cvo_lcm/status_t.hpp"

namespace cvo::test {

inline cvo_lcm::pose3d_t sample_pose(double seed) {
  cvo_lcm::pose3d_t p{};
  p.position[0] = seed;
  p.position[1] = -2 * seed;
  p.position[2] = 0.5 + seed;
  p.orientation[0] = 0.5;  // w, x, y, z of a unit quaternion
  p.orientation[1] = -0.5;
  p.orientation[2] = 0.5;
  p.orientation[3] = 0.5;
  return p;
}

inline cvo_lcm::graph_edge_t sample_edge(std::int64_t from, std::int64_t to) {
  cvo_lcm::graph_edge_t e{};
  e.from = from;
  e.to = to;
  e.measurement = sample_pose(0.1 * static_cast<double>(to));
  // Symmetric and diagonally dominant, so positive definite: an information matrix the back end's
  // door accepts (core/information.hpp). Entry (r, c) off the diagonal is 0.25 (6 min + max).
  for (int i = 0; i < 36; ++i) {
    const int r = i / 6, c = i % 6;
    e.information[i] = r == c ? 100.0 + i : 0.25 * (6 * std::min(r, c) + std::max(r, c));
  }
  return e;
}

inline cvo_lcm::rgbd_frame_t sample_rgbd() {
  cvo_lcm::rgbd_frame_t m{};
  m.version = cvo_lcm::rgbd_frame_t::SCHEMA_VERSION;
  m.utime = 1305031229528748;
  m.depth_utime = 1305031229528749;
  m.frame_index = 42;
  m.fx = 517.3;
  m.fy = 516.5;
  m.cx = 318.6;
  m.cy = 255.3;
  m.width = 4;
  m.height = 2;
  m.depth_scale = 5000;
  for (int i = 0; i < 5; ++i) m.distortion[i] = 0.25 - 0.125 * i;  // fr1-like magnitudes, exact in binary
  m.readout_s = 0.015625;
  m.colour_encoding = cvo_lcm::rgbd_frame_t::COLOUR_RAW_BGR8;
  m.depth_encoding = cvo_lcm::rgbd_frame_t::DEPTH_RAW_U16LE;
  for (int i = 0; i < 4 * 2 * 3; ++i) m.colour.push_back(static_cast<std::uint8_t>(7 * i));
  for (int i = 0; i < 4 * 2 * 2; ++i) m.depth.push_back(static_cast<std::uint8_t>(200 - i));
  m.colour_size = static_cast<std::int32_t>(m.colour.size());
  m.depth_size = static_cast<std::int32_t>(m.depth.size());
  return m;
}

inline cvo_lcm::pose_t sample_pose_message() {
  cvo_lcm::pose_t m{};
  m.version = cvo_lcm::pose_t::SCHEMA_VERSION;
  m.session = 0x5e5510'0000'0001;
  m.utime = 1305031229528748;
  m.frame_index = 7;
  m.keyframe_id = 3;
  m.odom_pose = sample_pose(1.0);
  m.map_pose = sample_pose(2.0);
  m.map_placed = true;
  for (int i = 0; i < 36; ++i) m.covariance[i] = 1e-4 * (i + 1);
  m.status = cvo_lcm::pose_t::STATUS_REGISTRATION_FAILED;
  m.is_keyframe = true;
  m.inner_product = 1234.5;
  m.gamma_frame = 0.91;
  m.gamma_keyframe = 0.72;
  m.iterations = 37;
  m.points = 9001;
  m.latency_ms = 12.25;
  m.robot = "hall-a";
  return m;
}

inline cvo_lcm::keyframe_t sample_keyframe() {
  cvo_lcm::keyframe_t m{};
  m.version = cvo_lcm::keyframe_t::SCHEMA_VERSION;
  m.session = 0x5e5510'0000'0001;
  m.id = 5;
  m.frame_index = 120;
  m.utime = 1305031233528748;
  m.pose = sample_pose(3.0);
  m.fx = 517.3;
  m.fy = 516.5;
  m.cx = 318.6;
  m.cy = 255.3;
  m.width = 640;
  m.height = 480;
  m.depth_scale = 5000;
  for (int i = 0; i < 5; ++i) m.distortion[i] = 0.5 - 0.25 * i;
  m.readout_s = 0.03125;
  m.colour_encoding = cvo_lcm::rgbd_frame_t::COLOUR_JPEG;
  m.depth_encoding = cvo_lcm::rgbd_frame_t::DEPTH_PNG;
  m.num_points = 3;
  for (int p = 0; p < m.num_points; ++p) {
    m.xyz.push_back({0.1f * p, -0.2f * p, 1.0f + p});
    m.labels.push_back({0.1f, 0.2f, 0.3f + p, 0.4f, 0.5f});
  }
  m.colour = {0xff, 0xd8, 0xff, 0xe0, 1, 2, 3};  // not a real JPEG: the wire format does not care
  m.depth = {0x89, 'P', 'N', 'G', 9, 8};
  m.colour_size = static_cast<std::int32_t>(m.colour.size());
  m.depth_size = static_cast<std::int32_t>(m.depth.size());
  m.robot = "hall-a";
  return m;
}

inline cvo_lcm::local_graph_t sample_local_graph() {
  cvo_lcm::local_graph_t m{};
  m.version = cvo_lcm::local_graph_t::SCHEMA_VERSION;
  m.session = 0x5e5510'0000'0001;
  m.keyframe_id = 5;
  m.utime = 1305031233528748;
  for (int n = 0; n < 3; ++n) {
    cvo_lcm::local_graph_node_t node{};
    node.frame_index = 120 + n;
    node.utime = 1305031233528748 + 33333 * n;
    node.pose = sample_pose(n);
    m.nodes.push_back(node);
  }
  m.edges = {sample_edge(120, 121), sample_edge(120, 122), sample_edge(121, 122)};
  m.num_nodes = static_cast<std::int32_t>(m.nodes.size());
  m.num_edges = static_cast<std::int32_t>(m.edges.size());
  m.robot = "hall-a";
  return m;
}

inline cvo_lcm::map_t sample_map() {
  cvo_lcm::map_t m{};
  m.version = cvo_lcm::map_t::SCHEMA_VERSION;
  m.utime = 1305031299000000;
  m.revision = 17;
  constexpr std::int64_t kFirst = 0x5e5510'0000'0001, kSecond = -0x2222'3333'4444'5555;
  const auto session = [](std::int64_t id, bool placed, std::int32_t keyframes, std::int64_t joined,
                          const cvo_lcm::pose3d_t& correction) {
    cvo_lcm::map_session_t s{};
    s.session = id;
    s.placed = placed;
    s.piece = id;
    s.keyframes = keyframes;
    s.joined_at_keyframe = joined;
    s.correction = correction;
    s.state = placed ? cvo_lcm::pose_t::STATE_LOCALIZED : cvo_lcm::pose_t::STATE_LOCALIZING;
    s.last_match_utime = placed ? 1305031102175304 : 0;
    s.covariance_keyframe = placed ? 2 : -1;
    for (int i = 0; i < 6; ++i) s.keyframe_covariance[i * 7] = placed ? 1e-4 : 0;
    return s;
  };
  m.sessions = {session(kFirst, true, 3, 0, sample_pose(0)), session(kSecond, false, 1, -1, sample_pose(1))};
  const std::int64_t ids[] = {0, 1, 2, 5};
  for (std::size_t i = 0; i < 4; ++i)
    m.keyframes.push_back(
        {i < 3 ? kFirst : kSecond, ids[i], 1305031233528748 + 100000 * ids[i], sample_pose(static_cast<double>(i))});
  m.loops = {{kFirst, kFirst, sample_edge(0, 2)}, {kFirst, kSecond, sample_edge(1, 5)}};
  m.num_sessions = static_cast<std::int32_t>(m.sessions.size());
  m.robots = {"hall-a", "dock.b_2"};
  m.num_keyframes = static_cast<std::int32_t>(m.keyframes.size());
  m.num_loops = static_cast<std::int32_t>(m.loops.size());
  return m;
}

inline cvo_lcm::map_correction_t sample_map_correction() {
  cvo_lcm::map_correction_t m{};
  m.version = cvo_lcm::map_correction_t::SCHEMA_VERSION;
  m.utime = 1305031299100000;
  m.epoch = 1305031200000000;
  m.revision = 18;
  m.session = sample_map().sessions[1];
  m.session.placed = true;
  m.session.state = cvo_lcm::pose_t::STATE_LOCALIZED;
  m.session.covariance_keyframe = 5;
  for (int i = 0; i < 6; ++i) m.session.keyframe_covariance[i * 7] = 2e-4;
  m.loops = {{5, 0x5e5510'0000'0001, 1, sample_pose(0.3), sample_pose(1.0)},
             {4, 0x5e5510'0000'0001, 0, sample_pose(0.4), sample_pose(0.0)}};
  m.num_loops = static_cast<std::int32_t>(m.loops.size());
  m.robot = "dock.b_2";
  return m;
}

inline cvo_lcm::status_t sample_status() {
  cvo_lcm::status_t m{};
  m.version = cvo_lcm::status_t::SCHEMA_VERSION;
  m.session = 0x5e5510'0000'0001;
  m.utime = 1305031299000000;
  m.pid = 4242;
  m.state = cvo_lcm::status_t::STATE_DEGRADED;
  m.rate_hz = 29.8;
  m.latency_median_ms = 18.5;
  m.latency_p99_ms = 31.0;
  m.deadline_misses = 3;
  m.dropped_frames = 11;
  m.failed_frames = 5;
  m.source_gaps = 1;
  m.allocations_after_warmup = 7;
  m.queue_depth = 2;
  m.rss_bytes = 123456789;
  for (int k = 0; k < cvo_lcm::status_t::NUM_BAD_KINDS; ++k) m.bad_messages[k] = 10 * k + 1;
  m.unsaved_records = 3;
  m.queue_drops = 4;
  m.keyframes_requested = 5;
  m.keyframes_recovered = 4;
  m.keyframes_lost = 1;
  m.process = "cvo-trackerd";
  m.detail = "camera re-opened after unplug";
  m.robot = "robot-7";
  return m;
}

inline cvo_lcm::keyframe_request_t sample_keyframe_request() {
  cvo_lcm::keyframe_request_t m{};
  m.version = cvo_lcm::keyframe_request_t::SCHEMA_VERSION;
  m.utime = 1305031299500000;
  m.session = 0x5e5510'0000'0001;
  m.ids = {3, 7, 12};
  m.num_ids = static_cast<std::int32_t>(m.ids.size());
  m.range_ids = {14, 15};
  m.range_messages = {cvo_lcm::keyframe_chunk_t::KEYFRAME, cvo_lcm::keyframe_chunk_t::LOCAL_GRAPH};
  m.range_first = {40, 0};
  m.range_count = {3, 1000};
  m.num_ranges = static_cast<std::int32_t>(m.range_ids.size());
  return m;
}

inline cvo_lcm::keyframe_chunk_t sample_keyframe_chunk() {
  cvo_lcm::keyframe_chunk_t m{};
  m.version = cvo_lcm::keyframe_chunk_t::SCHEMA_VERSION;
  m.session = 0x5e5510'0000'0001;
  m.id = 14;
  m.message = cvo_lcm::keyframe_chunk_t::KEYFRAME;
  m.message_size = 3 * cvo_lcm::keyframe_chunk_t::MAX_DATA - 17;
  m.message_crc = 0x1234abcd;
  m.index = 2;
  m.data.assign(cvo_lcm::keyframe_chunk_t::MAX_DATA - 17, 0xa5);
  m.data_size = static_cast<std::int32_t>(m.data.size());
  return m;
}

inline cvo_lcm::grid_t sample_grid() {
  cvo_lcm::grid_t m{};
  m.version = cvo_lcm::grid_t::SCHEMA_VERSION;
  m.utime = 1305031299600000;
  m.revision = 17;
  m.epoch = 1305031200000000;
  m.map_T_grid = sample_pose(0.25);
  m.up = cvo_lcm::grid_t::UP_ACCELEROMETER;
  m.resolution = 0.05;
  m.origin[0] = -1.25;
  m.origin[1] = 0.5;
  m.width = 3;
  m.height = 2;
  m.cells = {cvo_lcm::grid_t::CELL_UNKNOWN, cvo_lcm::grid_t::CELL_FREE,     cvo_lcm::grid_t::CELL_OCCUPIED,
             cvo_lcm::grid_t::CELL_FREE,    cvo_lcm::grid_t::CELL_OCCUPIED, cvo_lcm::grid_t::CELL_UNKNOWN};
  m.num_cells = static_cast<std::int32_t>(m.cells.size());
  m.frame = "grid";
  return m;
}

}  // namespace cvo::test
