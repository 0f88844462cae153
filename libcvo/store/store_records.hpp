#pragma once
// The keyframe store's file: its records and the scan that reads them back, for the store's writer
// (keyframe_store.hpp) and a read-only reader alike (read_store: cvo-map, cvo-run --mode localize).
// The format and why the scan keeps what it keeps: README.md ("The file", "Reading it").
#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace cvo::store {

// kMerge: a keyframe merged into one covering it (merge_record.hpp), after the keyframe's record.
// kSettled: what settled revisits left to a pair of keyframes (merge_record.hpp).
// kTally: a session's tally of settled revisits (merge_record.hpp), replacing its previous one.
// kDiscarded: records made garbage (keyframe_store.hpp: discard), named by where they lie in this
// file; a scan leaves them out, and the tombstone itself is garbage too. Payload: u32 count, then
// that many u64 offset, u32 bytes (little-endian).
enum class RecordKind : std::uint8_t {
  kKeyframe = 1,
  kLocalGraph = 2,
  kMerge = 3,
  kSettled = 4,
  kDiscarded = 5,
  kTally = 6
};

inline constexpr std::array<std::uint8_t, 8> kStoreMagic{'C', 'V', 'O', 'K', 'F', 'S', '1', '\n'};
inline constexpr std::size_t kRecordHeaderBytes = 16;  // before each payload

/// zlib's CRC-32 of `size` bytes, continuing `crc` (0 to start): the store's record checksum and
/// the receiver's fingerprint of a message's content.
std::uint32_t crc32_of(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0);

/// A record as the file holds it: header, then payload.
std::vector<std::uint8_t> encode_record(RecordKind kind, const std::vector<std::uint8_t>& payload);

/// Whether a valid record starts at `data + at` (`size` bytes in all): why not ("" when it does),
/// its size, and whether it looks like a record the end of the bytes cut short rather than damage.
struct RecordCheck {
  std::string why;
  std::size_t total = 0;  // header and payload
  bool cut_short = false;
};
RecordCheck check_record(const std::uint8_t* data, std::size_t size, std::size_t at);

/// An intact record: where it lies in the file.
struct IntactRecord {
  RecordKind kind = RecordKind::kKeyframe;
  std::size_t at = 0;     // its header's first byte
  std::size_t bytes = 0;  // header and payload
};

/// Bytes skipped, and why their first byte starts no record.
struct SkippedStretch {
  std::size_t at = 0, bytes = 0;
  std::string why;
};

/// A kDiscarded record's payload naming records at (offset, bytes).
std::vector<std::uint8_t> encode_discarded(const std::vector<std::pair<std::uint64_t, std::uint32_t>>& records);

struct StoreScan {
  std::vector<IntactRecord> records;    // in file order, the garbage left out
  std::vector<IntactRecord> garbage;    // intact records a tombstone names, and the tombstones; in file order
  std::vector<SkippedStretch> damaged;  // in file order
  std::optional<SkippedStretch> torn;   // a last record cut short by the end of the file
  [[nodiscard]] bool clean() const { return damaged.empty() && !torn; }
};

/// The bytes of a store file, scanned. Throws io::InputError naming `file` when they do not begin
/// with the store's magic (or as much of it as there is: a store whose creation was cut short
/// inside its magic scans as empty).
StoreScan scan_store(const std::filesystem::path& file, const std::uint8_t* data, std::size_t size);

/// What a scan skipped, for a warning: "FILE: 1 damaged stretch skipped (N bytes; the first at
/// byte X: why); the last record was cut short (N bytes at byte X, `torn_cause`) and `torn_fate`;
/// K intact records kept".
std::string describe_damage(const std::filesystem::path& file, const StoreScan& scan, const std::string& torn_cause,
                            const std::string& torn_fate);

/// A store file as it was when read, and its scan.
struct StoreSnapshot {
  std::vector<std::uint8_t> bytes;
  StoreScan scan;
  [[nodiscard]] const std::uint8_t* payload(const IntactRecord& r) const {
    return bytes.data() + r.at + kRecordHeaderBytes;
  }
  [[nodiscard]] static std::size_t payload_bytes(const IntactRecord& r) { return r.bytes - kRecordHeaderBytes; }
};

/// Reads the store at `file` without changing it: opened read-only, never written, renamed or cut,
/// so that it can be read while cvo-backendd appends to it (a record it is writing reads as a last
/// record cut short). Read, not mapped: the daemon cuts its file back after a failed write, and a
/// mapped page beyond the new end would kill the reader (SIGBUS). Throws io::InputError naming
/// `file` when it cannot be opened or read, or is not a keyframe store.
StoreSnapshot read_store(const std::filesystem::path& file);

}  // namespace cvo::store
