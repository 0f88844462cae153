#pragma once
// cvo-backendd's memory across restarts: every CVO_KEYFRAME and CVO_LOCAL_GRAPH it accepted,
// appended to one file as checksummed records, so that after a kill or a reboot it resumes with
// every keyframe it had received.
//
// File: the 8-byte magic "CVOKFS1\n", then records
//     u32 magic 0x4B465243 ("KFRC")  u8 kind  u8[3] zero  u32 payload bytes  u32 CRC-32 (zlib) of
//     kind + payload bytes, then the payload: the message's LCM encoding (fingerprint included)
// all little-endian. Records are only appended and flushed to disk (fdatasync) before append()
// returns, so a crash can only leave a partial last record. open() reads every record back; at
// the first one that is cut short or fails its checksum it stops, says so, and truncates the file
// there: a corrupt tail is dropped with a message, never loaded, and new records follow the last
// good one.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace cvo::daemon::backendd {

enum class RecordKind : std::uint8_t { kKeyframe = 1, kLocalGraph = 2 };

/// zlib's CRC-32 of `size` bytes, continuing `crc` (0 to start): the store's record checksum and
/// the receiver's fingerprint of a message's content.
std::uint32_t crc32_of(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0);

struct StoredRecord {
  RecordKind kind;
  std::vector<std::uint8_t> payload;
};

class KeyframeStore {
 public:
  /// Opens (creating it and its folder if needed) the store at `file` and reads it back. Throws
  /// io::InputError when the file cannot be created or read, or is not a keyframe store (wrong
  /// magic). `recovered` receives every intact record in order; `warning` says what was dropped
  /// ("" when nothing was).
  KeyframeStore(const std::filesystem::path& file, std::vector<StoredRecord>& recovered, std::string& warning);
  ~KeyframeStore();
  KeyframeStore(const KeyframeStore&) = delete;
  KeyframeStore& operator=(const KeyframeStore&) = delete;

  /// Appends one record durably; throws io::InputError on a write error (disk full, ...).
  void append(RecordKind kind, const std::vector<std::uint8_t>& payload);

  [[nodiscard]] const std::filesystem::path& file() const { return file_; }
  [[nodiscard]] std::uint64_t records() const { return records_; }

 private:
  std::filesystem::path file_;
  int fd_ = -1;
  std::uint64_t records_ = 0;
};

}  // namespace cvo::daemon::backendd
