#pragma once
// The keyframe store's records of revisits. The merge record (RecordKind::kMerge, store_records.hpp): "keyframe (s, k)
// was merged into keyframe (s', c) with T_c^k and this information", written after the keyframe's own record when the
// mapper merged it (slam/mapper.hpp: revisits). It carries what replaying the merge needs without the keyframe's record
// (its images): the keyframe's frame index, colour time and odometry pose, the merge's pose and information, and the
// keyframe's other verified loops in the order they were entered (slam::KeyframeMerge), so that a store whose merged
// keyframes' image records are dropped replays to the same map, with no loop detection for them.
//
// Not an LCM message: it never travels on the bus, only between the mapper and its own store.
// Payload, little-endian: u8 version (1), i64 session, id, frame, f64 timestamp, pose odometry,
// i64 covering session, covering id, pose relative, f64[36] information (row-major), f64 γ, then
// two lists (joining, others), each u32 count and that many loops: i64 from, to, pose
// measurement, f64[36] information, f64 η, α, i32 inliers. A pose is f64 tx ty tz qx qy qz qw.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "libcvo/slam/mapper.hpp"

namespace cvo::daemon::backendd {

inline constexpr std::uint8_t kMergeRecordVersion = 1;

// The settled record (RecordKind::kSettled): a settled edge (slam::SettledEdge) as the mapper's
// settle() left it, replacing the pair's previous record. Payload, little-endian: u8 version (1),
// i64 from session, from id, to session, to id, u8 robust (0 or 1), pose measurement, f64[36]
// information (row-major).
inline constexpr std::uint8_t kSettledRecordVersion = 1;
std::vector<std::uint8_t> encode_settled(const slam::SettledEdge& edge);
/// nullopt with *error when the bytes are not a settled record of this version.
std::optional<slam::SettledEdge> decode_settled(const std::uint8_t* data, std::size_t size, std::string* error);

// The tally record (RecordKind::kTally): a session's slam::SessionTally, replacing the session's
// previous one. Payload, little-endian: u8 version (1), i64 session, u64 forgotten, i64 settled
// through.
inline constexpr std::uint8_t kTallyRecordVersion = 1;
std::vector<std::uint8_t> encode_tally(const slam::SessionTally& tally);
std::optional<slam::SessionTally> decode_tally(const std::uint8_t* data, std::size_t size, std::string* error);

std::vector<std::uint8_t> encode_merge(const slam::KeyframeMerge& merge);
/// nullopt with *error when the bytes are not a merge record of this version (short, long, a
/// count beyond the bytes, a non-finite number).
std::optional<slam::KeyframeMerge> decode_merge(const std::uint8_t* data, std::size_t size, std::string* error);

}  // namespace cvo::daemon::backendd
