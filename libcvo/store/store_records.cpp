#include "libcvo/store/store_records.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <set>

#include "libcvo/io/input_error.hpp"

namespace cvo::store {
namespace {

namespace fs = std::filesystem;

constexpr std::uint32_t kRecordMagic = 0x4B465243;
constexpr std::array<std::uint8_t, 4> kRecordMagicBytes{0x43, 0x52, 0x46, 0x4B};  // kRecordMagic, little-endian
constexpr std::uint32_t kMaxPayload = 256u << 20;  // far above any keyframe; bounds a corrupt length

void put32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
std::uint32_t get32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

std::uint32_t checksum(std::uint8_t kind, const std::uint8_t* payload, std::size_t size) {
  return crc32_of(payload, size, crc32_of(&kind, 1));
}

bool known_kind(std::uint8_t kind) {
  return kind == static_cast<std::uint8_t>(RecordKind::kKeyframe) ||
         kind == static_cast<std::uint8_t>(RecordKind::kLocalGraph) ||
         kind == static_cast<std::uint8_t>(RecordKind::kMerge) ||
         kind == static_cast<std::uint8_t>(RecordKind::kSettled) ||
         kind == static_cast<std::uint8_t>(RecordKind::kDiscarded) ||
         kind == static_cast<std::uint8_t>(RecordKind::kTally);
}

std::uint64_t get64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

// What the tombstones among `s.records` name, moved with the tombstones into s.garbage. A name
// that is no intact record's start and size (it cannot be: the daemon names only its own) is
// ignored.
void set_garbage_aside(const std::uint8_t* data, StoreScan& s) {
  std::set<std::pair<std::uint64_t, std::uint64_t>> named;
  for (const auto& r : s.records) {
    if (r.kind != RecordKind::kDiscarded) continue;
    const std::uint8_t* p = data + r.at + kRecordHeaderBytes;
    const std::size_t bytes = r.bytes - kRecordHeaderBytes;
    const std::uint64_t n = bytes >= 4 ? get32(p) : 0;
    if (bytes != 4 + 12 * n) continue;
    for (std::uint64_t i = 0; i < n; ++i) named.insert({get64(p + 4 + 12 * i), get32(p + 12 + 12 * i)});
  }
  std::vector<IntactRecord> live;
  for (const auto& r : s.records)
    (r.kind == RecordKind::kDiscarded || named.contains({r.at, r.bytes}) ? s.garbage : live).push_back(r);
  s.records = std::move(live);
}

// Where the next valid record starts after `from` (`size` when none does): the record magic with
// a header, a length and a checksum that hold. Magic bytes inside a payload fail the checksum.
std::size_t resync(const std::uint8_t* data, std::size_t size, std::size_t from) {
  for (std::size_t at = from; at < size; ++at) {
    at = static_cast<std::size_t>(
        std::search(data + at, data + size, kRecordMagicBytes.begin(), kRecordMagicBytes.end()) - data);
    if (at < size && check_record(data, size, at).why.empty()) return at;
  }
  return size;
}

std::string count(std::size_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

}  // namespace

std::uint32_t crc32_of(const std::uint8_t* data, std::size_t size, std::uint32_t crc) {
  uLong c = crc;
  // zlib takes uInt lengths: feed large buffers in pieces.
  for (std::size_t at = 0; at < size;) {
    const auto n = static_cast<uInt>(std::min<std::size_t>(size - at, 1u << 30));
    c = crc32(c, data + at, n);
    at += n;
  }
  return static_cast<std::uint32_t>(c);
}

std::vector<std::uint8_t> encode_record(RecordKind kind, const std::vector<std::uint8_t>& payload) {
  std::vector<std::uint8_t> record(kRecordHeaderBytes + payload.size());
  put32(record.data(), kRecordMagic);
  record[4] = static_cast<std::uint8_t>(kind);
  put32(record.data() + 8, static_cast<std::uint32_t>(payload.size()));
  put32(record.data() + 12, checksum(static_cast<std::uint8_t>(kind), payload.data(), payload.size()));
  std::copy(payload.begin(), payload.end(), record.begin() + kRecordHeaderBytes);
  return record;
}

RecordCheck check_record(const std::uint8_t* data, std::size_t size, std::size_t at) {
  const std::uint8_t* h = data + at;
  const std::size_t left = size - at, have = std::min(left, kRecordHeaderBytes);
  // Only the header bytes the file still has are checked before calling a cut a torn write.
  for (std::size_t i = 0; i < std::min<std::size_t>(have, 4); ++i)
    if (h[i] != kRecordMagicBytes[i]) return {"bad record magic"};
  if (have > 4 && !known_kind(h[4])) return {"unknown record kind " + std::to_string(h[4])};
  for (std::size_t i = 5; i < std::min<std::size_t>(have, 8); ++i)
    if (h[i] != 0) return {"bad record header"};
  if (have < kRecordHeaderBytes) return {"record header cut short", 0, true};
  const auto bytes = get32(h + 8);
  if (bytes > kMaxPayload) return {"impossible record length " + std::to_string(bytes)};
  if (bytes > left - kRecordHeaderBytes)
    return {"record of " + std::to_string(bytes) + " bytes runs past the end of the file", 0, true};
  if (checksum(h[4], h + kRecordHeaderBytes, bytes) != get32(h + 12)) return {"checksum mismatch"};
  return {{}, kRecordHeaderBytes + bytes, false};
}

StoreScan scan_store(const fs::path& file, const std::uint8_t* data, std::size_t size) {
  if (!std::equal(data, data + std::min(size, kStoreMagic.size()), kStoreMagic.begin()))
    throw io::InputError(file, "not a cvo-backendd keyframe store (wrong magic); move it away to start afresh");
  StoreScan s;
  std::size_t at = kStoreMagic.size();
  while (at < size) {
    const auto check = check_record(data, size, at);
    if (check.why.empty()) {
      s.records.push_back({static_cast<RecordKind>(data[at + 4]), at, check.total});
      at += check.total;
      continue;
    }
    const auto next = resync(data, size, at + 1);
    SkippedStretch stretch{at, next - at, check.why};
    if (next == size && check.cut_short)
      s.torn = std::move(stretch);
    else
      s.damaged.push_back(std::move(stretch));
    at = next;
  }
  set_garbage_aside(data, s);
  return s;
}

std::vector<std::uint8_t> encode_discarded(const std::vector<std::pair<std::uint64_t, std::uint32_t>>& records) {
  std::vector<std::uint8_t> out(4 + 12 * records.size());
  put32(out.data(), static_cast<std::uint32_t>(records.size()));
  for (std::size_t i = 0; i < records.size(); ++i) {
    for (int b = 0; b < 8; ++b) out[4 + 12 * i + b] = static_cast<std::uint8_t>(records[i].first >> (8 * b));
    put32(out.data() + 12 + 12 * i, records[i].second);
  }
  return out;
}

// Built with append(): GCC 12 warns falsely (-Wrestrict) on chains of operator+.
std::string describe_damage(const fs::path& file, const StoreScan& s, const std::string& torn_cause,
                            const std::string& torn_fate) {
  std::string out = file.string();
  out.append(":");
  if (!s.damaged.empty()) {
    std::size_t bytes = 0;
    for (const auto& d : s.damaged) bytes += d.bytes;
    out.append(" ").append(count(s.damaged.size(), "damaged stretch", "damaged stretches"));
    out.append(" skipped (").append(count(bytes, "byte", "bytes"));
    out.append("; the first at byte ").append(std::to_string(s.damaged.front().at));
    out.append(": ").append(s.damaged.front().why).append(");");
  }
  if (s.torn) {
    out.append(" the last record was cut short (").append(count(s.torn->bytes, "byte", "bytes"));
    out.append(" at byte ").append(std::to_string(s.torn->at));
    out.append(", ").append(torn_cause).append(") and ").append(torn_fate).append(";");
  }
  return out.append(" ").append(count(s.records.size(), "intact record", "intact records")).append(" kept");
}

StoreSnapshot read_store(const fs::path& file) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw io::InputError(file, std::string("cannot open keyframe store: ") + std::strerror(errno));
  StoreSnapshot snapshot;
  struct stat st {};
  int error = ::fstat(fd, &st) != 0 ? errno : 0;
  if (error == 0 && !S_ISREG(st.st_mode)) error = EINVAL;
  if (error == 0) snapshot.bytes.resize(static_cast<std::size_t>(st.st_size));
  // The file may grow while it is read (only what it held at fstat is read) or be cut back (the
  // bytes end where it now ends).
  std::size_t done = 0;
  while (error == 0 && done < snapshot.bytes.size()) {
    const ssize_t n = ::pread(fd, snapshot.bytes.data() + done, snapshot.bytes.size() - done, static_cast<off_t>(done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) error = errno;
    if (n <= 0) break;
    done += static_cast<std::size_t>(n);
  }
  ::close(fd);
  if (error != 0)
    throw io::InputError(file, std::string("cannot read keyframe store: ") +
                                   (error == EINVAL ? "not a regular file" : std::strerror(error)));
  snapshot.bytes.resize(done);
  snapshot.scan = scan_store(file, snapshot.bytes.data(), snapshot.bytes.size());
  return snapshot;
}

}  // namespace cvo::store
