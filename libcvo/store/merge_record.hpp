#pragma once
// The keyframe store's records of revisits (RecordKind::kMerge, kSettled, kTally; store_records.hpp),
// encoded and decoded. Not LCM messages: they never travel on the bus. Their payloads, and why a
// merge record carries what it carries: README.md ("The file").
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "libcvo/slam/mapper.hpp"

namespace cvo::store {

inline constexpr std::uint8_t kMergeRecordVersion = 1;

// The settled record (RecordKind::kSettled): a settled edge (slam::SettledEdge) as the mapper's
// settle() left it, replacing the pair's previous record.
inline constexpr std::uint8_t kSettledRecordVersion = 1;
std::vector<std::uint8_t> encode_settled(const slam::SettledEdge& edge);
/// nullopt with *error when the bytes are not a settled record of this version.
std::optional<slam::SettledEdge> decode_settled(const std::uint8_t* data, std::size_t size, std::string* error);

// The tally record (RecordKind::kTally): a session's slam::SessionTally, replacing the session's
// previous one.
inline constexpr std::uint8_t kTallyRecordVersion = 1;
std::vector<std::uint8_t> encode_tally(const slam::SessionTally& tally);
std::optional<slam::SessionTally> decode_tally(const std::uint8_t* data, std::size_t size, std::string* error);

// The merge record (RecordKind::kMerge): keyframe (merge.session, merge.id) merged into the keyframe
// covering it, written after the keyframe's own record; it replays without that record (its images).
std::vector<std::uint8_t> encode_merge(const slam::KeyframeMerge& merge);
/// nullopt with *error when the bytes are not a merge record of this version (short, long, a
/// count beyond the bytes, a non-finite number).
std::optional<slam::KeyframeMerge> decode_merge(const std::uint8_t* data, std::size_t size, std::string* error);

}  // namespace cvo::store
