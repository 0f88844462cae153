#pragma once
// The keyframe store's writer: every CVO_KEYFRAME and CVO_LOCAL_GRAPH cvo-backendd accepted,
// appended durably (fdatasync) as checksummed records (store_records.hpp), so that a restart resumes
// with every keyframe received. On opening, a damaged store is recovered (its original kept beside
// it) and a torn last record cut off; discarded records are compacted away once they pass a quarter
// of the file; a record that cannot be written is held in memory, up to a bound, and written once
// writing works again. Why each: README.md ("Writing it").
#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "libcvo/store/store_records.hpp"

namespace cvo::store {

/// Where a record lies in the store file: the start of its header and its whole size. Lets a
/// reader that is behind take a record back from disk instead of holding it in memory, and a
/// record made garbage be named (discard()). A reference outlives one compaction (it is moved with
/// its record), not two.
struct RecordRef {
  off_t offset = 0;
  std::size_t bytes = 0;       // header and payload
  std::size_t generation = 0;  // compactions() when it was given
};

struct StoredRecord {
  RecordKind kind;
  std::vector<std::uint8_t> payload;
  RecordRef where{};  // a recovered record's place in the store as it is now (read() leaves it empty)
};

/// What became of an appended record.
enum class Appended {
  kStored,     // on disk
  kHeld,       // not written (the store fails); held in memory, written in order when it works again
  kNotDurable  // not written and the held records are at their bound: used this run, lost on restart
};

/// Whether the store keeps what it is given: for CVO_STATUS, systemd and the log.
struct StoreHealth {
  bool failing = false;           // the last write failed; new records are held
  int error = 0;                  // its errno (ENOSPC, EFBIG, EIO, ...)
  std::uint64_t unsaved = 0;      // records held in memory, not yet on disk
  std::uint64_t not_durable = 0;  // records of this run that could not be held: lost on restart
  /// Degraded while failing, and for the rest of the run once a record could not be kept.
  [[nodiscard]] bool degraded() const { return failing || not_durable > 0; }
};

/// "store full (12 records unsaved): No space left on device", "store at the file size limit
/// (...)", "store failing (...)", with what was lost ("3 records not kept: lost on restart");
/// "store writable" when healthy.
std::string describe(const StoreHealth& health);

class KeyframeStore {
 public:
  /// Opens (creating it and its folder if needed) the store at `file` and reads it back. Throws
  /// io::InputError when the file cannot be opened or read, or is not a keyframe store (wrong
  /// magic). `recovered` receives every intact record in order; `warning` says what was damaged,
  /// what was kept and where the damaged original went ("" when nothing was damaged). At most
  /// `unsaved_records_max` records are held in memory while writing fails (0: none).
  KeyframeStore(const std::filesystem::path& file, std::vector<StoredRecord>& recovered, std::string& warning,
                std::size_t unsaved_records_max = 0);
  ~KeyframeStore();
  KeyframeStore(const KeyframeStore&) = delete;
  KeyframeStore& operator=(const KeyframeStore&) = delete;

  /// Writes the held records, then this one, durably; never throws for a write error (only
  /// std::bad_alloc): the record is held, or counted as not durable (see Appended). When it is
  /// stored and `where` is given, `*where` says where (for read()).
  Appended append(RecordKind kind, const std::vector<std::uint8_t>& payload, RecordRef* where = nullptr);
  /// The record append() stored at `where`, read back from disk and checked as at recovery
  /// (magic, kind, length, checksum); nullopt with `*error` saying why when it cannot be.
  std::optional<StoredRecord> read(const RecordRef& where, std::string* error) const;
  /// Marks the record at `where` (given by append() or recovery) as garbage (see the header);
  /// compacts the file when garbage passes a quarter of it, nothing is held and the caller allows it
  /// (`may_compact`: false while it holds references it must still read, which could otherwise
  /// age past two compactions). True when it compacted; a failed compaction leaves the file as it
  /// was. A reference to no record of the store now (older than the last compaction's input, or
  /// garbage already) changes nothing.
  bool discard(const RecordRef& where, bool may_compact = true);
  /// `where` as the store is now (moved by the last compaction); nullopt when it is void.
  [[nodiscard]] std::optional<RecordRef> relocated(const RecordRef& where) const;
  /// Compactions so far.
  [[nodiscard]] std::size_t compactions() const { return compactions_; }
  /// Writes the held records, oldest first, as far as the store allows; true when none is left.
  bool retry();
  [[nodiscard]] StoreHealth health() const;

  [[nodiscard]] const std::filesystem::path& file() const { return file_; }
  /// Records on disk.
  [[nodiscard]] std::uint64_t records() const;

 private:
  void create();
  void recover(std::vector<StoredRecord>& recovered, std::string& warning);
  int write_at_end(const std::uint8_t* data, std::size_t size);
  bool write_held();
  bool compact();
  [[nodiscard]] std::optional<RecordRef> now_at(const RecordRef& where) const;

  std::filesystem::path file_;
  std::size_t held_max_;
  int fd_ = -1;
  mutable std::mutex mutex_;                    // cvo-receive appends; cvo-backend reads health()
  off_t end_ = 0;                               // end of the last complete record (0: magic not written yet)
  std::uint64_t records_ = 0;                   // on disk
  std::deque<std::vector<std::uint8_t>> held_;  // encoded records not yet written, oldest first
  StoreHealth health_;
  std::map<off_t, std::size_t> garbage_;  // discarded records: offset -> bytes
  std::size_t garbage_bytes_ = 0;
  std::size_t compactions_ = 0;
  std::vector<std::pair<off_t, std::size_t>> compacted_away_;  // the last compaction's garbage, by offset
};

}  // namespace cvo::store
