#pragma once
// cvo-trackerd's spool (trackerd.spool, issue 28): every keyframe and local graph it publishes, kept
// as a file until the back end acknowledges it (map_correction_t.acknowledged), so that a tracker
// started again after SIGKILL or a power cut finds the old sessions' messages and hands them over.
//
// One file per message, <session: 16 hex digits>-<keyframe id>-<k: keyframe | g: local graph>.lcm,
// the encoded message as published (its auth trailer zero: it is signed again when sent), written
// under a temporary name, flushed to the disk (fdatasync) and renamed into place, so a file with its
// final name is whole; a temporary one left by a crash is removed when the spool is opened. Bounded
// in bytes (trackerd.spool_bytes): past it the oldest messages go first, and are reported
// (dropped()). Used by the publisher thread only.
#include <cstdint>
#include <deque>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace cvo::daemon::trackerd {

/// An errno's text and name: "Read-only file system (EROFS)".
std::string errno_text(int error);

class Spool {
 public:
  struct Entry {
    std::int64_t session = 0;
    std::int64_t id = 0;
    bool graph = false;  // the keyframe's local graph, else the keyframe
    std::uintmax_t bytes = 0;
  };

  /// Why `dir` cannot be a spool ("" when it can): it cannot be created, or a file cannot be written
  /// and removed there (a read-only mount, a full disk, a file in the way), with the errno's text.
  static std::string unusable(const std::filesystem::path& dir);

  /// Opens (creates) the directory and takes in what it holds, oldest first; throws
  /// std::runtime_error naming the directory when it cannot be made or read.
  Spool(std::filesystem::path dir, std::uintmax_t max_bytes);

  /// Keeps a message; empty when kept, else why not, naming the errno (a full or failing disk: it
  /// is not kept, and the tracker goes on).
  std::string keep(const Entry& entry, std::span<const std::uint8_t> message);
  /// The message of an entry held, or nullopt (gone, or unreadable).
  [[nodiscard]] std::optional<std::vector<std::uint8_t>> read(const Entry& entry) const;
  /// Removes the session's messages of keyframes below `prefix` (acknowledged).
  void acknowledged(std::int64_t session, std::int64_t prefix);

  [[nodiscard]] const std::deque<Entry>& entries() const { return entries_; }  // oldest first
  [[nodiscard]] std::uintmax_t bytes() const { return bytes_; }
  /// Messages dropped for room since the last call.
  std::vector<Entry> dropped();

 private:
  [[nodiscard]] std::filesystem::path path_of(const Entry& entry) const;
  void remove(const Entry& entry);

  std::filesystem::path dir_;
  std::uintmax_t max_bytes_;
  std::deque<Entry> entries_;
  std::uintmax_t bytes_ = 0;
  std::vector<Entry> dropped_;
};

}  // namespace cvo::daemon::trackerd
