#pragma once
// Authenticated LCM messages: sign() writes a message's trailer in place on its encoding, verify()
// checks it on the raw received buffer before anything decodes it.
//
// Every cvo_lcm type sent on a channel ends with auth_t (proto/auth_t.lcm), fixed size, so the
// last kTrailerBytes of an encoded message m (n bytes) are: sender s, counter c, key id k (int64
// each, big-endian as LCM writes them) and the authenticator
//     a = BLAKE2b-256_K( len(channel) ‖ channel ‖ m[0, n - 32) )
// under the deployment key K whose id is k (libsodium's keyed crypto_generichash; len a big-endian
// uint32). Channel, fingerprint, body, s, c and k are all covered: a message cannot be changed,
// moved to another channel or claimed for another sender without K. Keyed BLAKE2b rather than
// crypto_auth (HMAC-SHA-512-256): a MAC by construction (no length extension to guard against) and
// measured faster (bench/auth_bench.cpp: 0.39 ms against 1.08 ms for a 300 kB keyframe, 1.5 µs against
// 4.9 µs for an 858-byte pose). The
// comparison is constant time (crypto_verify_32); the key is found by its id (key.hpp), so a
// receiver holding two keys (a rotation) computes one authenticator, not two.
//
// Replay: c = max(c_last + 1, wall clock in µs), strictly increasing per sender, and across the
// sender's restarts too (its clock has moved on; no state is kept on disk). Receivers take each
// (s, c) once and nothing older than auth.max_age_s (replay_window.hpp). Clocks must agree within
// max_age (NTP).
//
// Open bus (no key, auth.key_file none): sign() leaves the trailer zero, the bytes exactly as
// before; verify() accepts everything, and says so (authenticated false).
//
// A log read on purpose (a file:// provider) is a recording: verify() checks that it is authentic
// (Verifier without replay checks), not that it is new.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string_view>

#include "libcvo/auth/key.hpp"
#include "libcvo/auth/replay_window.hpp"

namespace cvo::auth {

inline constexpr std::size_t kTagBytes = 32;
inline constexpr std::size_t kTrailerBytes = 3 * 8 + kTagBytes;  // auth_t on the wire

/// The trailer's fields as they are on the wire (not yet trusted).
struct Trailer {
  std::int64_t sender = 0;
  std::int64_t counter = 0;
  std::int64_t key_id = 0;
};
/// Those of the last kTrailerBytes of `message` (size >= kTrailerBytes).
Trailer read_trailer(const std::uint8_t* message, std::size_t size);

class Signer {
 public:
  /// keys null: an open bus (nothing is signed). Thread-safe: one per process, shared by its threads.
  Signer(std::shared_ptr<const KeyRing> keys, std::int64_t sender);

  /// Writes the trailer into the last kTrailerBytes of `message` (an encoded cvo_lcm message, its
  /// trailer zero or from an earlier signing: a re-send is signed afresh). Throws
  /// std::invalid_argument for a message shorter than the trailer.
  void sign(std::string_view channel, std::span<std::uint8_t> message);

  [[nodiscard]] std::int64_t sender() const { return sender_; }
  [[nodiscard]] bool open() const { return keys_ == nullptr; }
  [[nodiscard]] const std::shared_ptr<const KeyRing>& keys() const { return keys_; }

 private:
  std::int64_t next_counter();

  std::shared_ptr<const KeyRing> keys_;
  std::int64_t sender_;
  std::atomic<std::int64_t> last_{0};
};

enum class Verdict { kOk, kAuth, kReplay };

struct Verification {
  Verdict verdict = Verdict::kAuth;
  std::int64_t sender = 0;  // kOk, kReplay: the authenticated sender; 0 on an open bus (one sender: anyone)
  bool authenticated = false;
  const char* why = "";  // why not (a static text)
};

class Verifier {
 public:
  /// keys null: an open bus (every message is kOk, unauthenticated). replay_checks false: a log
  /// read on purpose (authenticity only). Not thread-safe: one per receiving thread.
  Verifier(std::shared_ptr<const KeyRing> keys, std::int64_t max_age_us, bool replay_checks = true);

  /// The verdict on a raw buffer received on `channel`, at the receiver's wall time now_us.
  Verification verify(std::string_view channel, const void* data, std::size_t size, std::int64_t now_us);
  /// The same at the wall clock's now.
  Verification verify(std::string_view channel, const void* data, std::size_t size);

  [[nodiscard]] bool open() const { return keys_ == nullptr; }

 private:
  std::shared_ptr<const KeyRing> keys_;
  bool replay_checks_;
  ReplayWindow window_;
};

}  // namespace cvo::auth
