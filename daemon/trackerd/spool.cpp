#include "daemon/trackerd/spool.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <system_error>
#include <tuple>
#include <utility>

namespace cvo::daemon::trackerd {
namespace fs = std::filesystem;
namespace {

constexpr const char* kTemporary = ".partial";

// <session>-<id>-<k|g>.lcm -> the entry it names, or nullopt (not a spool file).
std::optional<Spool::Entry> parse_name(const std::string& name) {
  unsigned long long session = 0;
  long long id = 0;
  char kind = 0;
  int end = 0;
  if (std::sscanf(name.c_str(), "%16llx-%lld-%c.lcm%n", &session, &id, &kind, &end) != 3 ||
      end != static_cast<int>(name.size()) || id < 0 || (kind != 'k' && kind != 'g'))
    return std::nullopt;
  return Spool::Entry{static_cast<std::int64_t>(session), id, kind == 'g', 0};
}

// The bytes to `path`, flushed to the disk: 0, or the errno of the first step that failed.
int write_durably(const fs::path& path, std::span<const std::uint8_t> bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) return errno;
  int error = 0;
  for (std::size_t done = 0; done < bytes.size() && error == 0;) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) error = n < 0 ? errno : EIO;  // a write of nothing: the disk gave no room, nor a reason
    done += n > 0 ? static_cast<std::size_t>(n) : 0;
  }
  if (error == 0 && ::fdatasync(fd) != 0) error = errno;
  if (::close(fd) != 0 && error == 0) error = errno;
  return error;
}

// "cannot <what> <path>: Read-only file system (EROFS)": what an operator needs to act on it.
std::string failure(const std::string& what, const fs::path& path, int error) {
  return "cannot " + what + " " + path.string() + ": " + errno_text(error);
}

}  // namespace

std::string errno_text(int error) {
  const char* name = ::strerrorname_np(error);
  return std::error_code(error, std::generic_category()).message() + " (" +
         (name != nullptr ? std::string(name) : "errno " + std::to_string(error)) + ")";
}

std::string Spool::unusable(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return failure("create the directory", dir, ec.value());
  if (!fs::is_directory(dir, ec)) return failure("use", dir, ENOTDIR);
  // Root writes through a directory's mode bits: only trying shows a read-only mount or a full disk.
  const fs::path probe = dir / (".probe-" + std::to_string(::getpid()) + kTemporary);
  if (const int error = write_durably(probe, {}); error != 0) return failure("write in", dir, error);
  if (::unlink(probe.c_str()) != 0) return failure("remove", probe, errno);
  return {};
}

Spool::Spool(fs::path dir, std::uintmax_t max_bytes) : dir_(std::move(dir)), max_bytes_(max_bytes) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) throw std::runtime_error("trackerd.spool: " + failure("create the directory", dir_, ec.value()));
  std::vector<std::pair<fs::file_time_type, Entry>> found;
  for (const auto& file : fs::directory_iterator(dir_, ec)) {
    const std::string name = file.path().filename().string();
    if (name.ends_with(kTemporary)) {  // a write cut short: never renamed into place
      fs::remove(file.path(), ec);
      continue;
    }
    auto entry = parse_name(name);
    if (!entry || !file.is_regular_file(ec)) continue;
    entry->bytes = file.file_size(ec);
    found.emplace_back(file.last_write_time(ec), *entry);
  }
  if (ec) throw std::runtime_error("trackerd.spool: " + failure("read", dir_, ec.value()));
  // Oldest first; files written within the clock's resolution by name (a keyframe before its graph).
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) {
    return std::tie(a.first, a.second.session, a.second.id, a.second.graph) <
           std::tie(b.first, b.second.session, b.second.id, b.second.graph);
  });
  for (const auto& [time, entry] : found) {
    entries_.push_back(entry);
    bytes_ += entry.bytes;
  }
}

fs::path Spool::path_of(const Entry& e) const {
  char name[64];
  std::snprintf(name, sizeof name, "%016" PRIx64 "-%" PRId64 "-%c.lcm", static_cast<std::uint64_t>(e.session), e.id,
                e.graph ? 'g' : 'k');
  return dir_ / name;
}

void Spool::remove(const Entry& entry) {
  std::error_code ec;
  fs::remove(path_of(entry), ec);
  bytes_ -= std::min(bytes_, entry.bytes);
}

std::string Spool::keep(const Entry& entry, std::span<const std::uint8_t> message) {
  if (message.size() > max_bytes_) return "larger than trackerd.spool_bytes";
  while (!entries_.empty() && bytes_ + message.size() > max_bytes_) {  // the oldest go first
    dropped_.push_back(entries_.front());
    remove(entries_.front());
    entries_.pop_front();
  }
  const fs::path path = path_of(entry);
  fs::path temporary = path;
  temporary += kTemporary;
  if (const int error = write_durably(temporary, message); error != 0) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    return failure("write", temporary, error);
  }
  if (std::error_code ec; (fs::rename(temporary, path, ec), ec)) {
    fs::remove(temporary, ec);
    return failure("rename into place", temporary, ec.value());
  }
  entries_.push_back({entry.session, entry.id, entry.graph, message.size()});
  bytes_ += message.size();
  return {};
}

std::optional<std::vector<std::uint8_t>> Spool::read(const Entry& entry) const {
  std::ifstream in(path_of(entry), std::ios::binary);
  if (!in) return std::nullopt;
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return bytes;
}

void Spool::acknowledged(std::int64_t session, std::int64_t prefix) {
  std::erase_if(entries_, [&](const Entry& e) {
    const bool done = e.session == session && e.id < prefix;
    if (done) remove(e);
    return done;
  });
}

std::vector<Spool::Entry> Spool::dropped() { return std::exchange(dropped_, {}); }

}  // namespace cvo::daemon::trackerd
