#include "drivers/oni_file.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <system_error>

#include "libcvo/io/input_error.hpp"

namespace cvo::drivers {
namespace {

namespace fs = std::filesystem;

constexpr std::uint32_t kRecordMagic = 0x0052494E;  // "NIR\0" little-endian
constexpr std::uint32_t kNewData = 0x0A, kEnd = 0x0B, kNodeAdded1005 = 0x0C, kNodeAdded = 0x0D;
constexpr std::uint32_t kInvalidNode = 0xFFFFFFFFu;
constexpr std::size_t kFileHeaderBytes = 24;
constexpr std::size_t kMaxNodeIdOffset = 20;  // after the magic, the version and the max timestamp

// Little-endian fields, as every platform OpenNI records on writes them.
std::uint64_t le(const unsigned char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

std::string hex_start(const std::array<unsigned char, kFileHeaderBytes>& h, std::size_t n) {
  char text[16] = {};
  const std::size_t shown = std::min<std::size_t>(n, 4);
  for (std::size_t i = 0; i < shown; ++i) std::snprintf(text + 3 * i, 4, i + 1 < shown ? "%02x " : "%02x", h[i]);
  return text;
}

// The header's own checks, as OpenNI2's player makes them: magic, and a version from 1.0.0.4 to
// 1.0.1.0. Empty when it passes.
std::string header_problem(const std::array<unsigned char, kFileHeaderBytes>& h, std::size_t got, OniFileState& s) {
  if (got < 4 || std::memcmp(h.data(), "NI10", 4) != 0)
    return "not an ONI recording (it starts with " + (got == 0 ? std::string("nothing") : hex_start(h, got)) +
           ", not \"NI10\")";
  if (got < kFileHeaderBytes)
    return "truncated: " + std::to_string(got) + " bytes, shorter than the " + std::to_string(kFileHeaderBytes) +
           "-byte ONI header";
  const std::uint64_t version = (std::uint64_t{h[4]} << 48) | (std::uint64_t{h[5]} << 40) | (le(&h[6], 2) << 32) |
                                le(&h[8], 4);  // major, minor, maintenance, build: comparable in this order
  const std::uint64_t oldest = (std::uint64_t{1} << 48) | 4,
                      newest = (std::uint64_t{1} << 48) | (std::uint64_t{1} << 32);
  if (version < oldest || version > newest)
    return "ONI format version " + std::to_string(h[4]) + "." + std::to_string(h[5]) + "." +
           std::to_string(le(&h[6], 2)) + "." + std::to_string(le(&h[8], 4)) +
           ", which OpenNI2 cannot play (it reads 1.0.0.4 to 1.0.1.0)";
  s.record_header_bytes = version < newest ? 24 : 28;  // the 64-bit record header came with 1.0.1.0
  return {};
}

// Walks the records from after the header to the END record, or to the first that is not whole.
void scan_records(std::ifstream& in, std::uint32_t header_max_node, OniFileState& s) {
  std::uint64_t pos = kFileHeaderBytes;
  bool ended = false;
  std::array<unsigned char, 28> r{};
  while (pos + s.record_header_bytes <= s.size) {
    in.seekg(static_cast<std::streamoff>(pos));
    if (!in.read(reinterpret_cast<char*>(r.data()), s.record_header_bytes)) break;
    const auto fields = le(&r[12], 4), payload = le(&r[16], 4);
    if (le(&r[0], 4) != kRecordMagic || fields < s.record_header_bytes || pos + fields + payload > s.size) break;
    const auto type = static_cast<std::uint32_t>(le(&r[4], 4)), node = static_cast<std::uint32_t>(le(&r[8], 4));
    pos += fields + payload;
    if (type == kEnd) {
      ended = true;
      break;
    }
    if (node != kInvalidNode) s.max_node_id = std::max(s.max_node_id, node);
    if (type == kNewData) {
      ++s.data_records;
      ++s.frames_per_node[node];
    }
    if (type == kNodeAdded || type == kNodeAdded1005)
      s.nodes_added.push_back({pos - fields - payload, type, node, static_cast<std::uint32_t>(fields)});
  }
  s.usable_bytes = pos;
  s.truncated = !ended && pos < s.size;
  s.closed = ended && header_max_node >= s.max_node_id;
}

}  // namespace

std::string OniFileState::summary() const {
  const std::string frames = std::to_string(data_records) + " frames of all streams";
  if (closed) return "closed, " + frames;
  return std::string(truncated ? "cut off in a record" : "never closed") + ": " + frames + " whole in " +
         std::to_string(usable_bytes) + " of " + std::to_string(size) + " bytes";
}

OniFileState inspect_oni(const fs::path& file) {
  OniFileState s;
  std::error_code ec;
  const auto status = fs::status(file, ec);
  if (!fs::exists(status)) {
    s.problem = "no such file";
    return s;
  }
  if (!fs::is_regular_file(status)) {
    s.problem = "not a regular file";
    return s;
  }
  s.size = fs::file_size(file, ec);
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    s.problem = std::string("cannot be read: ") + std::strerror(errno);
    return s;
  }
  std::array<unsigned char, kFileHeaderBytes> h{};
  in.read(reinterpret_cast<char*>(h.data()), h.size());
  const auto got = static_cast<std::size_t>(in.gcount());
  in.clear();
  if (s.problem = header_problem(h, got, s); !s.problem.empty()) return s;
  scan_records(in, static_cast<std::uint32_t>(le(&h[kMaxNodeIdOffset], 4)), s);
  if (s.data_records == 0)
    s.problem = std::string("holds no frame (") +
                (s.truncated ? "cut off"
                 : s.closed  ? "closed"
                             : "never closed") +
                " after " + std::to_string(s.usable_bytes) + " bytes)";
  return s;
}

namespace {

void write_le(std::fstream& out, std::uint64_t at, std::uint64_t value, int bytes) {
  std::array<char, 8> b{};
  for (int i = 0; i < bytes; ++i) b[static_cast<std::size_t>(i)] = static_cast<char>(value >> (8 * i));
  out.seekp(static_cast<std::streamoff>(at));
  out.write(b.data(), bytes);
}

// A NODE_ADDED record ends with: frame count (4 bytes), min and max timestamps (8 each), and in
// its newest form the seek table's position (8 bytes; 4 in the 32-bit format).
void patch_node_added(std::fstream& out, const OniFileState& s, const OniFileState::NodeAdded& n) {
  const auto frames = s.frames_per_node.contains(n.node) ? s.frames_per_node.at(n.node) : 0u;
  std::uint64_t tail = n.position + n.fields;
  if (n.type == kNodeAdded) {
    const int seek_bytes = s.record_header_bytes == 28 ? 8 : 4;
    tail -= static_cast<std::uint64_t>(seek_bytes);
    write_le(out, tail, 0, seek_bytes);  // no seek table
  }
  write_le(out, tail - 20, frames, 4);
}

}  // namespace

void repair_oni_copy(const fs::path& file, const OniFileState& state, const fs::path& copy) {
  std::error_code ec;
  fs::copy_file(file, copy, fs::copy_options::overwrite_existing, ec);
  if (!ec) fs::resize_file(copy, state.usable_bytes, ec);
  if (ec) throw io::InputError(copy, "cannot write a repaired copy of " + file.string() + ": " + ec.message());
  std::fstream out(copy, std::ios::binary | std::ios::in | std::ios::out);
  write_le(out, kMaxNodeIdOffset, state.max_node_id, 4);
  for (const auto& n : state.nodes_added) patch_node_added(out, state, n);
  // The END record: its header alone.
  const std::uint64_t end = state.usable_bytes;
  write_le(out, end, kRecordMagic, 4);
  write_le(out, end + 4, kEnd, 4);
  write_le(out, end + 8, 0, 4);
  write_le(out, end + 12, state.record_header_bytes, 4);
  write_le(out, end + 16, 0, 4);                                                 // payload size
  write_le(out, end + 20, 0, static_cast<int>(state.record_header_bytes) - 20);  // undo position
  if (!out.flush()) throw io::InputError(copy, "cannot write a repaired copy of " + file.string());
}

bool is_oni_path(const std::string& uri) {
  std::string tail = uri.size() >= 4 ? uri.substr(uri.size() - 4) : uri;
  std::transform(tail.begin(), tail.end(), tail.begin(), [](unsigned char c) { return std::tolower(c); });
  if (tail == ".oni") return true;
  std::error_code ec;
  return !uri.empty() && fs::is_regular_file(uri, ec);
}

}  // namespace cvo::drivers
