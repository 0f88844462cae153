#pragma once
// The deployment key: 32 random bytes that every daemon of one deployment holds, and the key file
// that carries up to two of them (auth.key_file; made by cvo-keygen).
//
// Rotation without stopping the fleet: a file holds one or two keys; the first signs, every one
// verifies, so daemons holding {A} and {A, B} interoperate (both sign with A), and so do {A, B} and
// {B, A}, and {B, A} and {B}. cvo-keygen steps a file through them, each step rolled out to every
// daemon (restarted one by one) before the next: `--add` {A} -> {A, B}, `--rotate` {A, B} -> {B, A},
// `--retire` {B, A} -> {B} (systemd/README.md).
//
// A key is named on the wire by its id, the first 8 bytes of BLAKE2b-256("cvo-slam key id" ‖ key),
// so a receiver picks the key without trying each; the id does not reveal the key. Secrets live
// only in memory that libsodium guards (sodium_malloc: guard pages, locked, read-only once filled)
// and zeroes when freed (the file's text too).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "libcvo/io/input_error.hpp"

namespace cvo::auth {

inline constexpr std::size_t kKeyBytes = 32;

/// Calls sodium_init() (idempotent, thread-safe); throws std::runtime_error when libsodium cannot start.
void init_sodium();

/// A secret key in guarded memory, move-only.
class Key {
 public:
  /// 32 bytes from the kernel's random generator (randombytes_buf).
  static Key generate();
  /// From 64 hex digits (no other character); nullopt otherwise.
  static std::optional<Key> from_hex(std::string_view hex);

  Key(Key&& other) noexcept;
  Key& operator=(Key&& other) noexcept;
  Key(const Key&) = delete;
  Key& operator=(const Key&) = delete;
  ~Key();

  [[nodiscard]] const unsigned char* bytes() const { return bytes_; }
  [[nodiscard]] std::int64_t id() const { return id_; }

 private:
  Key();  // allocates the guarded bytes, writable until seal()
  void seal();

  unsigned char* bytes_ = nullptr;
  std::int64_t id_ = 0;
};

/// The key id of 32 key bytes (never 0: 0 marks an unsigned message).
std::int64_t key_id(const unsigned char* key);

/// "0x0123456789abcdef": how notes and cvo-keygen name a key (its id, never the key).
std::string key_name(std::int64_t id);

/// The keys of a key file: the first signs, each verifies.
class KeyRing {
 public:
  static constexpr std::size_t kMaxKeys = 2;
  /// Throws std::invalid_argument for no key, more than kMaxKeys, or two with one id.
  explicit KeyRing(std::vector<Key> keys);

  [[nodiscard]] const Key& signing() const { return keys_.front(); }
  /// The key with this id; nullptr when this ring has none (another deployment's, a retired one).
  [[nodiscard]] const Key* find(std::int64_t id) const;
  [[nodiscard]] std::span<const Key> keys() const { return keys_; }
  /// The keys, to build another ring from (cvo-keygen's rotate and retire); this ring is left empty.
  std::vector<Key> release() { return std::move(keys_); }

 private:
  std::vector<Key> keys_;
};

/// A key file that cannot be used; the message names the file and says what to do.
class KeyFileError : public io::InputError {
 public:
  using io::InputError::InputError;
};

/// The key file's text, parsed:
///     cvo-slam key file 1
///     key <64 hex digits>    (signs)
///     key <64 hex digits>    (optional: accepted too, the key before a rotation)
/// '#' starts a comment, blank lines are skipped. Throws KeyFileError (file:line) for another
/// first line, a malformed key line, no key, more than two or a repeated key.
KeyRing parse_key_file(std::string_view text, const std::filesystem::path& name_for_errors);

/// Reads a key file. Throws KeyFileError when it is missing or unreadable, when its mode lets its
/// group or others in (it must be 0600 or stricter: chmod 600), when it is over 4 KiB, or as
/// parse_key_file.
KeyRing read_key_file(const std::filesystem::path& file);

/// Writes `keys` as a new file, mode 0600. Throws KeyFileError when the file exists (a key is
/// never overwritten by accident) or cannot be written.
void create_key_file(const std::filesystem::path& file, const KeyRing& keys);

/// Replaces an existing key file with `keys` (rotate, retire): written beside it with mode 0600,
/// flushed, then renamed over it, so a reader sees the old file or the new one, never a part.
void replace_key_file(const std::filesystem::path& file, const KeyRing& keys);

}  // namespace cvo::auth
