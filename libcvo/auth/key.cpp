#include "libcvo/auth/key.hpp"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>
#include <stdexcept>
#include <utility>

namespace cvo::auth {
namespace {

constexpr std::string_view kFirstLine = "cvo-slam key file 1";
constexpr std::size_t kMaxFileBytes = 4096;
constexpr std::size_t kHexDigits = 2 * kKeyBytes;

// Bytes in guarded memory, zeroed when freed: the key file's text.
class SecureBuffer {
 public:
  explicit SecureBuffer(std::size_t size) : data_(static_cast<char*>(sodium_malloc(size))), size_(size) {
    if (data_ == nullptr) throw std::bad_alloc();
  }
  ~SecureBuffer() { sodium_free(data_); }
  SecureBuffer(const SecureBuffer&) = delete;
  SecureBuffer& operator=(const SecureBuffer&) = delete;
  [[nodiscard]] char* data() const { return data_; }
  [[nodiscard]] std::size_t size() const { return size_; }

 private:
  char* data_;
  std::size_t size_;
};

// Closes a file descriptor on every path.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  [[nodiscard]] int get() const { return fd_; }
  int release() { return std::exchange(fd_, -1); }

 private:
  int fd_;
};

std::string errno_text() { return std::strerror(errno); }

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

// The file's text: a comment line, the version line, one line per key (with its id as a comment).
std::size_t write_text(const KeyRing& keys, SecureBuffer& out) {
  std::size_t used = 0;
  const auto append = [&](std::string_view s) {
    if (used + s.size() > out.size()) throw std::length_error("key file text");
    for (const char c : s) out.data()[used++] = c;  // (memcpy here: GCC 12 warns of a bound it cannot see)
  };
  append("# cvo-slam deployment key (cvo-keygen): secret, mode 0600. The first key signs, every key verifies.\n");
  append(kFirstLine);
  append("\n");
  for (const auto& key : keys.keys()) {
    append("key ");
    if (used + kHexDigits + 1 > out.size()) throw std::length_error("key file text");
    sodium_bin2hex(out.data() + used, kHexDigits + 1, key.bytes(), kKeyBytes);
    used += kHexDigits;
    append("  # id " + key_name(key.id()) + "\n");
  }
  return used;
}

void write_all(int fd, const char* data, std::size_t size, const std::filesystem::path& file) {
  while (size > 0) {
    const auto n = write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw KeyFileError(file, "cannot write: " + errno_text());
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  if (fsync(fd) != 0) throw KeyFileError(file, "cannot write: " + errno_text());
}

void write_keys(int fd, const KeyRing& keys, const std::filesystem::path& file) {
  if (fchmod(fd, 0600) != 0) throw KeyFileError(file, "cannot make it mode 0600: " + errno_text());
  SecureBuffer text(kMaxFileBytes);
  write_all(fd, text.data(), write_text(keys, text), file);
}

}  // namespace

void init_sodium() {
  if (sodium_init() < 0) throw std::runtime_error("libsodium cannot be initialised");
}

Key::Key() : bytes_(static_cast<unsigned char*>(sodium_malloc(kKeyBytes))) {
  if (bytes_ == nullptr) throw std::bad_alloc();
}

void Key::seal() {
  id_ = key_id(bytes_);
  sodium_mprotect_readonly(bytes_);
}

Key::Key(Key&& other) noexcept : bytes_(std::exchange(other.bytes_, nullptr)), id_(std::exchange(other.id_, 0)) {}

Key& Key::operator=(Key&& other) noexcept {
  if (this != &other) {
    if (bytes_ != nullptr) sodium_free(bytes_);
    bytes_ = std::exchange(other.bytes_, nullptr);
    id_ = std::exchange(other.id_, 0);
  }
  return *this;
}

Key::~Key() {
  if (bytes_ != nullptr) sodium_free(bytes_);  // zeroes the bytes first
}

Key Key::generate() {
  init_sodium();
  Key key;
  randombytes_buf(key.bytes_, kKeyBytes);
  key.seal();
  return key;
}

std::optional<Key> Key::from_hex(std::string_view hex) {
  init_sodium();
  if (hex.size() != kHexDigits) return std::nullopt;
  Key key;
  std::size_t length = 0;
  const char* end = nullptr;
  if (sodium_hex2bin(key.bytes_, kKeyBytes, hex.data(), hex.size(), nullptr, &length, &end) != 0 ||
      length != kKeyBytes || end != hex.data() + hex.size())
    return std::nullopt;
  key.seal();
  return key;
}

std::int64_t key_id(const unsigned char* key) {
  static constexpr std::string_view kDomain = "cvo-slam key id";
  unsigned char hash[crypto_generichash_BYTES];
  crypto_generichash_state state;
  crypto_generichash_init(&state, nullptr, 0, sizeof hash);
  crypto_generichash_update(&state, reinterpret_cast<const unsigned char*>(kDomain.data()), kDomain.size());
  crypto_generichash_update(&state, key, kKeyBytes);
  crypto_generichash_final(&state, hash, sizeof hash);
  std::uint64_t id = 0;
  for (int i = 0; i < 8; ++i) id = (id << 8) | hash[i];
  return id == 0 ? 1 : static_cast<std::int64_t>(id);
}

std::string key_name(std::int64_t id) {
  char text[24];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(id));
  return text;
}

KeyRing::KeyRing(std::vector<Key> keys) : keys_(std::move(keys)) {
  if (keys_.empty()) throw std::invalid_argument("a key ring needs a key");
  if (keys_.size() > kMaxKeys) throw std::invalid_argument("a key ring holds at most two keys (new and old)");
  if (keys_.size() == 2 && keys_[0].id() == keys_[1].id()) throw std::invalid_argument("the same key twice");
}

const Key* KeyRing::find(std::int64_t id) const {
  for (const auto& key : keys_)
    if (key.id() == id) return &key;
  return nullptr;
}

KeyRing parse_key_file(std::string_view text, const std::filesystem::path& name) {
  std::vector<Key> keys;
  bool versioned = false;
  std::size_t number = 0;
  while (!text.empty()) {
    const auto newline = text.find('\n');
    std::string_view line = text.substr(0, newline);
    text = newline == std::string_view::npos ? std::string_view{} : text.substr(newline + 1);
    ++number;
    line = trim(line.substr(0, line.find('#')));
    if (line.empty()) continue;
    if (!versioned) {
      if (line != kFirstLine)
        throw KeyFileError(name, number,
                           "not a cvo-slam key file of this version (its first line must be '" +
                               std::string(kFirstLine) + "'; cvo-keygen makes one)");
      versioned = true;
      continue;
    }
    if (!line.starts_with("key ") && !line.starts_with("key\t"))
      throw KeyFileError(name, number, "expected 'key' and 64 hex digits");
    auto key = Key::from_hex(trim(line.substr(4)));
    if (!key) throw KeyFileError(name, number, "a key is 64 hex digits (32 bytes)");
    if (keys.size() == KeyRing::kMaxKeys)
      throw KeyFileError(name, number, "more than two keys (a rotation holds the new key and the old one)");
    if (!keys.empty() && keys.front().id() == key->id()) throw KeyFileError(name, number, "the same key twice");
    keys.push_back(std::move(*key));
  }
  if (keys.empty()) throw KeyFileError(name, versioned ? "holds no key" : "is empty: not a cvo-slam key file");
  return KeyRing(std::move(keys));
}

KeyRing read_key_file(const std::filesystem::path& file) {
  init_sodium();
  const Fd fd(open(file.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0) throw KeyFileError(file, "cannot open the key file: " + errno_text());
  struct stat st {};
  if (fstat(fd.get(), &st) != 0) throw KeyFileError(file, "cannot stat the key file: " + errno_text());
  if (!S_ISREG(st.st_mode)) throw KeyFileError(file, "is not a regular file");
  if ((st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    throw KeyFileError(file, std::string("has mode ") + mode +
                                 ": its group or others may read the deployment key; it must be 0600 or "
                                 "stricter (chmod 600 " +
                                 file.string() + ")");
  }
  if (st.st_size > static_cast<off_t>(kMaxFileBytes)) throw KeyFileError(file, "is too large for a key file");
  SecureBuffer text(kMaxFileBytes);
  std::size_t used = 0;
  while (used < text.size()) {
    const auto n = read(fd.get(), text.data() + used, text.size() - used);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw KeyFileError(file, "cannot read the key file: " + errno_text());
    if (n == 0) break;
    used += static_cast<std::size_t>(n);
  }
  return parse_key_file({text.data(), used}, file);
}

void create_key_file(const std::filesystem::path& file, const KeyRing& keys) {
  Fd fd(open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600));
  if (fd.get() < 0) {
    if (errno == EEXIST) throw KeyFileError(file, "exists already: a key file is never overwritten");
    throw KeyFileError(file, "cannot create the key file: " + errno_text());
  }
  try {
    write_keys(fd.get(), keys, file);
  } catch (...) {
    std::filesystem::remove(file);  // no half-written key file is left behind
    throw;
  }
}

void replace_key_file(const std::filesystem::path& file, const KeyRing& keys) {
  std::string temporary = file.string() + ".XXXXXX";
  Fd fd(mkstemp(temporary.data()));  // mode 0600
  if (fd.get() < 0) throw KeyFileError(file, "cannot write beside the key file: " + errno_text());
  try {
    write_keys(fd.get(), keys, temporary);
    if (close(fd.release()) != 0) throw KeyFileError(temporary, "cannot write: " + errno_text());
    if (rename(temporary.c_str(), file.c_str()) != 0)
      throw KeyFileError(file, "cannot replace the key file: " + errno_text());
  } catch (...) {
    std::filesystem::remove(temporary);
    throw;
  }
}

}  // namespace cvo::auth
