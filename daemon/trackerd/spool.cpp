#include "daemon/trackerd/spool.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cinttypes>
#include <cstdio>
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

bool write_durably(const fs::path& path, std::span<const std::uint8_t> bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) return false;
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n <= 0) break;
    done += static_cast<std::size_t>(n);
  }
  const bool ok = done == bytes.size() && ::fdatasync(fd) == 0;
  return ::close(fd) == 0 && ok;
}

}  // namespace

Spool::Spool(fs::path dir, std::uintmax_t max_bytes) : dir_(std::move(dir)), max_bytes_(max_bytes) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) throw std::runtime_error("trackerd.spool " + dir_.string() + ": " + ec.message());
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
  if (ec) throw std::runtime_error("trackerd.spool " + dir_.string() + ": " + ec.message());
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
  std::error_code ec;
  if (!write_durably(temporary, message) || (fs::rename(temporary, path, ec), ec)) {
    fs::remove(temporary, ec);
    return "cannot write " + path.string() + " (a full or failing disk?)";
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
