#include "libcvo/store/keyframe_store.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <optional>

#include "libcvo/io/input_error.hpp"

namespace cvo::store {
namespace {

namespace fs = std::filesystem;

// 0, or the errno of the failure (after a partial write: of the call that failed).
int write_all_at(int fd, const std::uint8_t* p, std::size_t size, off_t at) {
  while (size > 0) {
    const ssize_t n = ::pwrite(fd, p, size, at);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return errno;
    if (n == 0) return EIO;
    p += n;
    at += n;
    size -= static_cast<std::size_t>(n);
  }
  return 0;
}

// A new or renamed file's name survives a crash only once its folder is flushed too.
void fsync_folder(const fs::path& file) {
  const auto folder = file.has_parent_path() ? file.parent_path() : fs::path(".");
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;     // nothing more can be done; the file's own data is durable
  if (::fsync(fd) != 0) { /* as above */
  }
  ::close(fd);
}

std::string count(std::size_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

// ---------------------------------------------------------------------------------------------
// Reading back (the scan itself: store_records.hpp)

struct Range {
  std::size_t at = 0, bytes = 0;
};

// The file's bytes outside every skipped stretch (after its magic): its intact records, in order.
// What a clean copy leaves out: the damaged stretches and the garbage, by offset.
std::vector<std::pair<off_t, std::size_t>> left_out(const StoreScan& s) {
  std::vector<std::pair<off_t, std::size_t>> out;
  for (const auto& d : s.damaged) out.emplace_back(static_cast<off_t>(d.at), d.bytes);
  for (const auto& g : s.garbage) out.emplace_back(static_cast<off_t>(g.at), g.bytes);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<Range> intact_ranges(const StoreScan& s, std::size_t size) {
  std::vector<Range> out;
  std::size_t from = kStoreMagic.size();
  const auto add = [&](std::size_t to) {
    if (to > from) out.push_back({from, to - from});
  };
  for (const auto& [at, bytes] : left_out(s)) {
    add(static_cast<std::size_t>(at));
    from = static_cast<std::size_t>(at) + bytes;
  }
  add(s.torn ? s.torn->at : size);
  return out;
}

// Where the byte at `at` lies once the stretches `removed` (by offset, ascending) are cut out of the
// file; nullopt when it lies inside one of them.
template <typename Stretches, typename Bounds>
std::optional<off_t> after_removing(off_t at, const Stretches& removed, Bounds bounds) {
  off_t shift = 0;
  for (const auto& stretch : removed) {
    const auto [from, bytes] = bounds(stretch);
    if (from > at) break;
    if (at < from + static_cast<off_t>(bytes)) return std::nullopt;
    shift += static_cast<off_t>(bytes);
  }
  return at - shift;
}

// The file, mapped read-only while it is read back (no copy of a large store in memory).
class Mapping {
 public:
  Mapping(int fd, std::size_t size, const fs::path& file) : size_(size) {
    if (size == 0) return;
    void* p = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
    if (p == MAP_FAILED) throw io::InputError(file, std::string("cannot read keyframe store: ") + std::strerror(errno));
    data_ = static_cast<const std::uint8_t*>(p);
  }
  ~Mapping() {
    if (data_ != nullptr) ::munmap(const_cast<std::uint8_t*>(data_), size_);
  }
  Mapping(const Mapping&) = delete;
  Mapping& operator=(const Mapping&) = delete;
  [[nodiscard]] const std::uint8_t* data() const { return data_; }

 private:
  const std::uint8_t* data_ = nullptr;
  std::size_t size_;
};

// ---------------------------------------------------------------------------------------------
// Replacing a damaged store

std::string utc_stamp() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y%m%dT%H%M%SZ", &utc);
  return text;
}

// The damaged original under a new name, FILE.damaged-<UTC time>[-N]: a hard link, so that FILE
// still holds it until the clean copy replaces it. Empty with `error` when it cannot be made.
fs::path keep_aside(const fs::path& file, std::string& error) {
  const std::string base = file.string() + ".damaged-" + utc_stamp();
  for (int n = 1; n < 100; ++n) {
    const std::string name = n == 1 ? base : base + "-" + std::to_string(n);
    if (::link(file.c_str(), name.c_str()) == 0) return name;
    if (errno != EEXIST) {
      error = "cannot keep the damaged original as " + name + ": " + std::strerror(errno);
      return {};
    }
  }
  error = "too many damaged copies named " + base;
  return {};
}

struct CleanCopy {
  int fd = -1;  // the clean store, now at FILE; -1 with `error` when there is none
  off_t size = 0;
  fs::path aside;
  std::string error;
};

// Writes the intact ranges of `data` to FILE.recovering, makes it durable, keeps the original
// aside (when `keep_original`: a damaged one) and renames the copy over FILE. A crash at any point
// leaves FILE whole (the original or the complete copy); on a failure nothing but FILE is left.
CleanCopy replace_with_clean_copy(const fs::path& file, const std::uint8_t* data, const std::vector<Range>& intact,
                                  mode_t mode, bool keep_original = true) {
  const fs::path temp = file.string() + ".recovering";
  CleanCopy copy;
  copy.fd = ::open(temp.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, mode & 07777);
  if (copy.fd < 0) return {-1, 0, {}, "cannot create " + temp.string() + ": " + std::strerror(errno)};
  int error = write_all_at(copy.fd, kStoreMagic.data(), kStoreMagic.size(), 0);
  copy.size = static_cast<off_t>(kStoreMagic.size());
  for (const auto& r : intact) {
    if (error == 0) error = write_all_at(copy.fd, data + r.at, r.bytes, copy.size);
    copy.size += static_cast<off_t>(r.bytes);
  }
  if (error == 0 && ::fsync(copy.fd) != 0) error = errno;
  if (error != 0)
    copy.error = "cannot write " + temp.string() + ": " + std::strerror(error);
  else
    copy.aside = keep_original ? keep_aside(file, copy.error) : file;
  if (!copy.aside.empty() && ::rename(temp.c_str(), file.c_str()) != 0) {
    const int rename_error = errno;
    copy.error = "cannot rename " + temp.string() + ": " + std::strerror(rename_error);
    if (keep_original) ::unlink(copy.aside.c_str());
    copy.aside.clear();
  }
  if (copy.aside.empty()) {
    ::close(copy.fd);
    ::unlink(temp.c_str());
    return {-1, 0, {}, copy.error};
  }
  fsync_folder(file);
  return copy;
}

}  // namespace

std::string describe(const StoreHealth& health) {
  std::string out;
  if (health.failing) {
    const char* what = health.error == ENOSPC || health.error == EDQUOT ? "store full"
                       : health.error == EFBIG                          ? "store at the file size limit"
                                                                        : "store failing";
    out = std::string(what) + " (" + count(health.unsaved, "record", "records") +
          " unsaved): " + std::strerror(health.error);
  }
  if (health.not_durable > 0)
    out += (out.empty() ? "store: " : "; ") + count(health.not_durable, "record", "records") +
           " not kept (the unsaved records were at their bound): lost on restart";
  return out.empty() ? "store writable" : out;
}

KeyframeStore::KeyframeStore(const fs::path& file, std::vector<StoredRecord>& recovered, std::string& warning,
                             std::size_t unsaved_records_max)
    : file_(file), held_max_(unsaved_records_max) {
  std::error_code ec;
  if (file.has_parent_path()) fs::create_directories(file.parent_path(), ec);
  fd_ = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0640);
  if (fd_ < 0) throw io::InputError(file, std::string("cannot open keyframe store: ") + std::strerror(errno));
  try {
    recover(recovered, warning);
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

KeyframeStore::~KeyframeStore() {
  if (fd_ >= 0) ::close(fd_);
}

// A new store (or one whose creation was cut short inside the magic): the magic is written, or
// held like a record when even that cannot be written: the daemon starts degraded rather than not
// at all.
void KeyframeStore::create() {
  end_ = 0;
  if (::ftruncate(fd_, 0) != 0) { /* write_held() writes over what is there */
  }
  write_held();
}

void KeyframeStore::recover(std::vector<StoredRecord>& recovered, std::string& warning) {
  struct stat st {};
  if (::fstat(fd_, &st) != 0)
    throw io::InputError(file_, std::string("cannot read keyframe store: ") + std::strerror(errno));
  const auto size = static_cast<std::size_t>(st.st_size);
  const Mapping map(fd_, size, file_);
  const std::uint8_t* data = map.data();
  const StoreScan s = scan_store(file_, data, size);
  if (size < kStoreMagic.size()) return create();

  const std::size_t first = recovered.size();
  for (const auto& r : s.records)
    recovered.push_back(
        {r.kind, {data + r.at + kRecordHeaderBytes, data + r.at + r.bytes}, {static_cast<off_t>(r.at), r.bytes, 0}});
  records_ = s.records.size() + s.garbage.size();
  garbage_bytes_ = 0;
  for (const auto& g : s.garbage) {
    garbage_.emplace(static_cast<off_t>(g.at), g.bytes);
    if (g.kind != RecordKind::kDiscarded) garbage_bytes_ += g.bytes;
  }
  end_ = static_cast<off_t>(size);
  if (s.clean()) return;
  warning = describe_damage(file_, s, "as a crash during a write leaves it", "is cut off");
  if (!s.damaged.empty()) {
    const auto copy = replace_with_clean_copy(file_, data, intact_ranges(s, size), st.st_mode);
    if (copy.fd >= 0) {
      const auto removed = left_out(s);
      for (std::size_t i = first; i < recovered.size(); ++i) {  // the copy leaves out damage and garbage
        auto& where = recovered[i].where;
        where.offset = after_removing(where.offset, removed, [](const auto& r) { return r; }).value_or(0);
      }
      ::close(fd_);
      fd_ = copy.fd;
      end_ = copy.size;
      records_ = s.records.size();
      garbage_.clear();
      garbage_bytes_ = 0;
      warning += "; the damaged original is kept as " + copy.aside.string() + ", and " + file_.string() +
                 " now holds the intact records";
      return;
    }
    warning += "; no clean copy could be written (" + copy.error + "): the damaged stretches stay in " +
               file_.string() + " and are skipped at every start";
  }
  if (s.torn) {
    // Shrinking needs no space. Should it fail, the next record is written over the cut one.
    end_ = static_cast<off_t>(s.torn->at);
    if (::ftruncate(fd_, end_) != 0 || ::fdatasync(fd_) != 0)
      warning += "; cutting off the cut record failed (" + std::string(std::strerror(errno)) + ")";
  }
}

// The file's magic if it is not on disk yet, then the held records, oldest first. Under mutex_
// (or in the constructor).
bool KeyframeStore::write_held() {
  const auto failed = [&](int error) {
    health_.failing = true;
    health_.error = error;
    return false;
  };
  if (end_ == 0) {
    if (const int error = write_at_end(kStoreMagic.data(), kStoreMagic.size()); error != 0) return failed(error);
    fsync_folder(file_);
  }
  while (!held_.empty()) {
    const auto& record = held_.front();
    if (const int error = write_at_end(record.data(), record.size()); error != 0) return failed(error);
    // Garbage itself, never copied; not counted towards a compaction (it is small, and what it
    // names is).
    if (record[4] == static_cast<std::uint8_t>(RecordKind::kDiscarded))
      garbage_.emplace(end_ - static_cast<off_t>(record.size()), record.size());
    held_.pop_front();
    ++records_;
  }
  health_.failing = false;
  health_.error = 0;
  return true;
}

// Writes at the end of the last complete record and flushes: 0, or the errno. A failure cuts the
// file back there, so that no torn record stays in front of the next one.
int KeyframeStore::write_at_end(const std::uint8_t* data, std::size_t size) {
  int error = write_all_at(fd_, data, size, end_);
  if (error == 0 && ::fdatasync(fd_) != 0) error = errno;
  if (error == 0) {
    end_ += static_cast<off_t>(size);
    return 0;
  }
  if (::ftruncate(fd_, end_) != 0) { /* the next write at end_ goes over what is left */
  }
  return error;
}

Appended KeyframeStore::append(RecordKind kind, const std::vector<std::uint8_t>& payload, RecordRef* where) {
  auto record = encode_record(kind, payload);
  const std::size_t bytes = record.size();
  const std::lock_guard lock(mutex_);
  held_.push_back(std::move(record));  // behind every record held before it: the order is kept
  if (write_held()) {
    if (where != nullptr) *where = {end_ - static_cast<off_t>(bytes), bytes, compactions_};  // written last
    return Appended::kStored;
  }
  if (held_.size() <= held_max_) return Appended::kHeld;
  held_.pop_back();
  ++health_.not_durable;
  return Appended::kNotDurable;
}

// `where` as the store is now: moved by the last compaction when it was given before it. Under mutex_.
std::optional<RecordRef> KeyframeStore::now_at(const RecordRef& where) const {
  if (where.generation == compactions_) return where;
  if (where.generation + 1 != compactions_) return std::nullopt;
  const auto at = after_removing(where.offset, compacted_away_, [](const auto& g) { return g; });
  if (!at) return std::nullopt;
  return RecordRef{*at, where.bytes, compactions_};
}

std::optional<RecordRef> KeyframeStore::relocated(const RecordRef& where) const {
  const std::lock_guard lock(mutex_);
  return now_at(where);
}

bool KeyframeStore::discard(const RecordRef& given, bool may_compact) {
  const std::lock_guard lock(mutex_);
  const auto where = now_at(given);
  if (!where || where->offset < static_cast<off_t>(kStoreMagic.size()) ||
      where->offset + static_cast<off_t>(where->bytes) > end_)
    return false;
  if (!garbage_.emplace(where->offset, where->bytes).second) return false;
  garbage_bytes_ += where->bytes;
  // Its tombstone, so that a restart does not replay it (written, or held in order as any record).
  held_.push_back(encode_record(
      RecordKind::kDiscarded,
      encode_discarded({{static_cast<std::uint64_t>(where->offset), static_cast<std::uint32_t>(where->bytes)}})));
  if (!write_held() && held_.size() > held_max_) {
    held_.pop_back();  // not kept: nothing is lost, the record only replays again after a restart
  }
  if (!may_compact || !held_.empty() || 4 * garbage_bytes_ <= static_cast<std::size_t>(end_)) return false;
  return compact();
}

// The records outside garbage_, copied as a damaged store's intact ones are (replace_with_clean_copy,
// the original not kept). Under mutex_.
bool KeyframeStore::compact() {
  struct stat st {};
  if (::fstat(fd_, &st) != 0) return false;
  const auto size = static_cast<std::size_t>(end_);
  const Mapping map(fd_, size, file_);
  std::vector<Range> live;
  std::size_t from = kStoreMagic.size();
  for (const auto& [at, bytes] : garbage_) {
    if (static_cast<std::size_t>(at) > from) live.push_back({from, static_cast<std::size_t>(at) - from});
    from = static_cast<std::size_t>(at) + bytes;
  }
  if (size > from) live.push_back({from, size - from});
  const auto copy = replace_with_clean_copy(file_, map.data(), live, st.st_mode, /*keep_original=*/false);
  if (copy.fd < 0) return false;  // left as it was: its garbage replays harmlessly, and is tried again later
  ::close(fd_);
  fd_ = copy.fd;
  end_ = copy.size;
  records_ -= garbage_.size();
  compacted_away_.assign(garbage_.begin(), garbage_.end());
  garbage_.clear();
  garbage_bytes_ = 0;
  ++compactions_;
  return true;
}

std::optional<StoredRecord> KeyframeStore::read(const RecordRef& given, std::string* error) const {
  const auto fail = [&](const std::string& why) -> std::optional<StoredRecord> {
    if (error != nullptr)
      *error = "record at byte " + std::to_string(given.offset) + " of " + file_.string() + ": " + why;
    return std::nullopt;
  };
  const std::lock_guard lock(mutex_);  // a compaction replaces fd_
  const auto where = now_at(given);
  if (!where) return fail("compacted away");
  if (where->offset < static_cast<off_t>(kStoreMagic.size()) || where->bytes < kRecordHeaderBytes ||
      where->offset + static_cast<off_t>(where->bytes) > end_)
    return fail("not within the records written");
  std::vector<std::uint8_t> bytes(where->bytes);
  for (std::size_t done = 0; done < bytes.size();) {  // records below end_ are never written again
    const ssize_t n = ::pread(fd_, bytes.data() + done, bytes.size() - done, where->offset + static_cast<off_t>(done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return fail(std::strerror(errno));
    if (n == 0) return fail("the file ends before it");
    done += static_cast<std::size_t>(n);
  }
  const auto check = check_record(bytes.data(), bytes.size(), 0);
  if (!check.why.empty()) return fail(check.why);
  if (check.total != bytes.size()) return fail("its length is not the one written");
  return StoredRecord{static_cast<RecordKind>(bytes[4]), {bytes.begin() + kRecordHeaderBytes, bytes.end()}};
}

bool KeyframeStore::retry() {
  const std::lock_guard lock(mutex_);
  return !health_.failing || write_held();
}

StoreHealth KeyframeStore::health() const {
  const std::lock_guard lock(mutex_);
  StoreHealth h = health_;
  h.unsaved = held_.size();
  return h;
}

std::uint64_t KeyframeStore::records() const {
  const std::lock_guard lock(mutex_);
  return records_;
}

}  // namespace cvo::store
