#pragma once
// An .oni file's state, read before OpenNI is given it: OpenNI's player says nothing useful about
// a file it cannot play (a missing file, a text file, an unclosed recording all fail with an empty
// reason), and a recording that was never closed (the recorder killed, the disk full, the cable
// pulled) fails to open although its frames are all there.
//
// The ONI layout (OpenNI2's Source/Drivers/OniFile/DataRecords.h, read to understand, not copied):
// a 24-byte header (magic "NI10", a 4-part version, the global max timestamp, the max node id that
// the recorder patches when it closes the file), then records, each a header (magic "NIR\0", type,
// node id, the size of the header and its fields, the payload's size, the undo position: 24 bytes
// before format 1.0.1.0, 28 from it) followed by its payload, ending with an END record (type 0x0B).
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace cvo::drivers {

struct OniFileState {
  std::string problem;                     // why OpenNI cannot play it at all; empty: it can, maybe repaired
  std::uint64_t size = 0;                  // bytes in the file
  std::uint64_t usable_bytes = 0;          // the header and every whole record, up to the END record
  std::uint32_t max_node_id = 0;           // the largest node id a record names
  std::uint64_t data_records = 0;          // frames (NEW_DATA records) of every stream
  std::uint32_t record_header_bytes = 28;  // 24 in files older than format 1.0.1.0 (OpenNI 1)
  // Where each stream's NODE_ADDED record is (its frame count and seek table are patched when the
  // file is closed) and the frames each stream holds.
  struct NodeAdded {
    std::uint64_t position = 0;
    std::uint32_t type = 0, node = 0, fields = 0;
  };
  std::vector<NodeAdded> nodes_added;
  std::map<std::uint32_t, std::uint32_t> frames_per_node;
  bool closed = false;     // ends with an END record and a patched header
  bool truncated = false;  // a partial record after the last whole one

  /// Playable only through a repaired copy (repair_oni_copy).
  [[nodiscard]] bool needs_repair() const { return problem.empty() && !closed; }
  /// One line for the log: "closed, 120 frames" or "never closed: 57 whole frames, cut in a record".
  [[nodiscard]] std::string summary() const;
};

/// Reads the file's header and record headers (seeking over payloads: fast on large files).
/// Never throws: what is wrong is in `problem` (missing, not a regular file, unreadable, shorter
/// than a header, not an ONI recording, a format version OpenNI2 cannot read, no frame at all).
OniFileState inspect_oni(const std::filesystem::path& file);

/// Writes to `copy` the usable part of `file` with what closing it would have written: the header's
/// max node id, each stream's frame count (without a seek table: one past the cut would fail the
/// open) and an END record. Throws io::InputError naming the file when it cannot.
void repair_oni_copy(const std::filesystem::path& file, const OniFileState& state, const std::filesystem::path& copy);

/// Whether an openni2: URI names a file rather than a device: it ends in ".oni" (any case) or is
/// an existing regular file. Devices are re-opened with back-off; a file that fails stays failed.
bool is_oni_path(const std::string& uri);

}  // namespace cvo::drivers
