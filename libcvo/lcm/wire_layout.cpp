#include "libcvo/lcm/wire_layout.hpp"

#include <algorithm>
#include <array>

namespace cvo::lcm {
namespace {

// Wire sizes of the embedded types (proto/*.lcm).
constexpr int kPose3d = 7 * 8;                        // position[3], orientation[4]
constexpr int kGraphNode = 8 + 8 + kPose3d;           // frame_index, utime, pose
constexpr int kGraphEdge = 8 + 8 + kPose3d + 36 * 8;  // from, to, measurement, information

// rgbd_frame_t: version, utime, depth_utime, frame_index (28), fx fy cx cy (60), width height (68),
// depth_scale (76), distortion[5] (116), readout_s (124), two encodings (126), then the counts.
constexpr std::array kRgbdCounts{CountField{"colour_size", 126, 1}, CountField{"depth_size", 130, 1}};
// keyframe_t: version, session, id, frame_index, utime (36), pose (92), fx..cy (124), width height
// (132), depth_scale (140), distortion[5] (180), readout_s (188), two encodings (190), then the
// counts; a point is xyz[3] + labels[5] floats.
constexpr std::array kKeyframeCounts{CountField{"num_points", 190, 8 * 4}, CountField{"colour_size", 194, 1},
                                     CountField{"depth_size", 198, 1}};
// local_graph_t: version, session, keyframe_id, utime (28), then the counts.
constexpr std::array kLocalGraphCounts{CountField{"num_nodes", 28, kGraphNode},
                                       CountField{"num_edges", 32, kGraphEdge}};
// map_t: version, utime, revision, epoch (28), then the counts of map_session_t (session, placed, piece,
// keyframes, joined_at_keyframe, correction, state, visitor, last_match_utime, covariance_keyframe,
// keyframe_covariance[36]), map_keyframe_t (session, id, utime, pose) and map_loop_t (two
// sessions, an edge).
constexpr int kMapSession = 8 + 1 + 8 + 4 + 8 + kPose3d + 1 + 1 + 8 + 8 + 36 * 8;
constexpr int kMapKeyframe = 8 + 8 + 8 + kPose3d;
constexpr int kMapLoop = 8 + 8 + kGraphEdge;
constexpr std::array kMapCounts{CountField{"num_sessions", 28, kMapSession},
                                CountField{"num_keyframes", 32, kMapKeyframe}, CountField{"num_loops", 36, kMapLoop}};
// map_correction_t: version, utime, epoch, revision, acknowledged (36), the session's map_session_t
// (427), then the count of map_correction_loop_t (keyframe, other_session, other_keyframe,
// measurement, other_pose).
constexpr int kCorrectionLoop = 8 + 8 + 8 + kPose3d + kPose3d;
constexpr std::array kMapCorrectionCounts{CountField{"num_loops", 36 + kMapSession, kCorrectionLoop}};
// keyframe_request_t: version, utime, session (20), then the counts of int64 ids and of ranges (an
// int64 keyframe id, an int8 message, two int32: first slice, count).
constexpr std::array kKeyframeRequestCounts{CountField{"num_ids", 20, 8}, CountField{"num_ranges", 24, 8 + 1 + 4 + 4}};
// keyframe_chunk_t: version, session, id (20), message (21), message_size, message_crc, index (33),
// then the count of data bytes.
constexpr std::array kKeyframeChunkCounts{CountField{"data_size", 33, 1}};
// grid_t: version, utime, revision, epoch (28), map_T_grid (84), up (85), resolution (93),
// origin[3] (117), width height (125), then the count of int8 cells, and the string frame after them.
constexpr std::array kGridCounts{CountField{"num_cells", 125, 1}};

std::int32_t read_be32(const std::uint8_t* p) {
  return static_cast<std::int32_t>((std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) |
                                   (std::uint32_t{p[2]} << 8) | std::uint32_t{p[3]});
}

}  // namespace

WireLayout wire_layout(std::string_view type_name) {
  if (type_name == "rgbd_frame_t") return {134, kRgbdCounts};
  // keyframe_t, local_graph_t: the string robot after the arrays; map_t: robots, one per session.
  if (type_name == "keyframe_t") return {202, kKeyframeCounts, kStringsAfterArrays, 1};
  if (type_name == "local_graph_t") return {36, kLocalGraphCounts, kStringsAfterArrays, 1};
  if (type_name == "map_t") return {40, kMapCounts, kStringsAfterArrays, 0, 0};
  if (type_name == "map_correction_t") return {36 + kMapSession + 4, kMapCorrectionCounts, kStringsAfterArrays, 1};
  // pose_t: version, session, utime, frame_index, keyframe_id (36), two poses (148), two booleans
  // (150), epoch, revision (166), state (167), since_match_s (175), covariance[36] (463), a boolean
  // (464), relative_covariance[36] (752), status, is_keyframe (754), 3 doubles (778), 2 int32 (786),
  // latency_ms (794), then the string robot.
  if (type_name == "pose_t") return {794, {}, 794, 1};
  if (type_name == "keyframe_request_t") return {28, kKeyframeRequestCounts};
  if (type_name == "keyframe_chunk_t") return {37, kKeyframeChunkCounts};
  if (type_name == "grid_t") return {129, kGridCounts, kStringsAfterArrays, 1};
  // status_t: version, session, utime, pid, state (25), 3 doubles (49), 5 int64 (89), queue_depth
  // (93), rss_bytes (101), bad_messages[17] (237), 5 int64 (277), bus (278), sender (286), then the
  // strings process, detail and robot (then auth, as in every type).
  if (type_name == "status_t") return {286, {}, 286, 3};
  return {};
}

std::string check_counts(const WireLayout& layout, const std::uint8_t* body, int size) {
  if (size < layout.header_bytes) return {};
  std::int64_t needed = layout.header_bytes;  // 64-bit: counts up to 2^31 times up to 376 bytes
  std::int64_t num_strings = layout.num_strings;
  for (std::size_t i = 0; i < layout.counts.size(); ++i) {
    const auto& field = layout.counts[i];
    const std::int32_t count = read_be32(body + field.offset);
    if (count < 0) return "negative count " + std::string(field.name) + " = " + std::to_string(count);
    needed += std::int64_t{count} * field.bytes_per_element;
    if (static_cast<int>(i) == layout.strings_counted_by) num_strings += count;
  }
  if (needed > size)
    return "truncated body: its counts need at least " + std::to_string(needed) + " bytes, it has " +
           std::to_string(size);
  // needed <= size: the arrays end within the body.
  const int strings_at = layout.strings_at == kStringsAfterArrays ? static_cast<int>(needed) : layout.strings_at;
  for (std::int64_t i = 0, at = strings_at; i < num_strings; ++i) {
    if (size - at < 4) return {};                      // truncated: the lcm-gen decoder says so
    const std::int32_t length = read_be32(body + at);  // includes the terminating NUL
    if (length < 1 || length > size - at - 4)
      return "corrupt string length " + std::to_string(length) + " at body offset " + std::to_string(at);
    // Exactly one NUL, the last byte: lcm-gen's decoder keeps inner NULs that its encoder (strlen)
    // drops, so such a string would not survive a round trip (found by fuzz/status).
    const std::uint8_t* text = body + at + 4;
    if (text[length - 1] != 0 || std::find(text, text + length - 1, std::uint8_t{0}) != text + length - 1)
      return "string at body offset " + std::to_string(at) + " is not one NUL-terminated text";
    at += 4 + length;
  }
  return {};
}

}  // namespace cvo::lcm

namespace cvo::lcm::detail {

std::string hex64(std::uint64_t v) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string s = "0x0000000000000000";
  for (int i = 17; i >= 2; --i, v >>= 4) s[static_cast<std::size_t>(i)] = kDigits[v & 0xf];
  return s;
}

}  // namespace cvo::lcm::detail
