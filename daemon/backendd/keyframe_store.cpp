#include "daemon/backendd/keyframe_store.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

#include "libcvo/io/input_error.hpp"

namespace cvo::daemon::backendd {
namespace {

constexpr std::array<char, 8> kFileMagic{'C', 'V', 'O', 'K', 'F', 'S', '1', '\n'};
constexpr std::uint32_t kRecordMagic = 0x4B465243;
constexpr std::size_t kHeaderBytes = 16;
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

bool read_exactly(int fd, void* buffer, std::size_t size) {
  auto* p = static_cast<std::uint8_t*>(buffer);
  while (size > 0) {
    const ssize_t n = ::read(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

bool write_all(int fd, const std::uint8_t* p, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
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

KeyframeStore::KeyframeStore(const std::filesystem::path& file, std::vector<StoredRecord>& recovered,
                             std::string& warning)
    : file_(file) {
  std::error_code ec;
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path(), ec);
  fd_ = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0640);
  if (fd_ < 0) throw io::InputError(file, std::string("cannot open keyframe store: ") + std::strerror(errno));

  const off_t size = ::lseek(fd_, 0, SEEK_END);
  ::lseek(fd_, 0, SEEK_SET);
  if (size == 0) {
    if (!write_all(fd_, reinterpret_cast<const std::uint8_t*>(kFileMagic.data()), kFileMagic.size()) || ::fdatasync(fd_) != 0)
      throw io::InputError(file, std::string("cannot write keyframe store: ") + std::strerror(errno));
    return;
  }
  std::array<char, 8> magic{};
  if (!read_exactly(fd_, magic.data(), magic.size()) || magic != kFileMagic) {
    ::close(fd_);
    fd_ = -1;
    throw io::InputError(file, "not a cvo-backendd keyframe store (wrong magic); move it away to start afresh");
  }

  off_t good_end = static_cast<off_t>(kFileMagic.size());
  while (good_end < size) {
    std::array<std::uint8_t, kHeaderBytes> header{};
    const auto why = [&]() -> std::string {
      if (!read_exactly(fd_, header.data(), header.size())) return "record header cut short";
      if (get32(header.data()) != kRecordMagic) return "bad record magic";
      const auto kind = header[4];
      if (kind != static_cast<std::uint8_t>(RecordKind::kKeyframe) && kind != static_cast<std::uint8_t>(RecordKind::kLocalGraph))
        return "unknown record kind " + std::to_string(kind);
      const auto bytes = get32(header.data() + 8);
      if (bytes > kMaxPayload || static_cast<off_t>(bytes) > size - good_end - static_cast<off_t>(kHeaderBytes))
        return "record of " + std::to_string(bytes) + " bytes runs past the end of the file";
      StoredRecord record{static_cast<RecordKind>(kind), std::vector<std::uint8_t>(bytes)};
      if (!read_exactly(fd_, record.payload.data(), bytes)) return "record cut short";
      if (checksum(kind, record.payload.data(), bytes) != get32(header.data() + 12)) return "checksum mismatch";
      recovered.push_back(std::move(record));
      return {};
    }();
    if (!why.empty()) {
      warning = file.string() + ": dropped " + std::to_string(size - good_end) + " bytes after record " +
                std::to_string(records_) + " (" + why + ")";
      if (::ftruncate(fd_, good_end) != 0 || ::fdatasync(fd_) != 0)
        throw io::InputError(file, std::string("cannot truncate the corrupt tail: ") + std::strerror(errno));
      break;
    }
    good_end = ::lseek(fd_, 0, SEEK_CUR);
    ++records_;
  }
  ::lseek(fd_, good_end, SEEK_SET);
}

KeyframeStore::~KeyframeStore() {
  if (fd_ >= 0) ::close(fd_);
}

void KeyframeStore::append(RecordKind kind, const std::vector<std::uint8_t>& payload) {
  std::vector<std::uint8_t> record(kHeaderBytes + payload.size());
  put32(record.data(), kRecordMagic);
  record[4] = static_cast<std::uint8_t>(kind);
  put32(record.data() + 8, static_cast<std::uint32_t>(payload.size()));
  put32(record.data() + 12, checksum(static_cast<std::uint8_t>(kind), payload.data(), payload.size()));
  std::copy(payload.begin(), payload.end(), record.begin() + kHeaderBytes);
  const off_t start = ::lseek(fd_, 0, SEEK_END);
  if (!write_all(fd_, record.data(), record.size()) || ::fdatasync(fd_) != 0) {
    const std::string error = std::strerror(errno);
    if (::ftruncate(fd_, start) != 0) { /* the next open() drops the partial record */ }
    throw io::InputError(file_, "cannot append a record: " + error);
  }
  ++records_;
}

}  // namespace cvo::daemon::backendd
