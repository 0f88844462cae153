#include "libcvo/auth/authenticator.hpp"

#include <sodium.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>

namespace cvo::auth {
namespace {

static_assert(crypto_generichash_KEYBYTES == kKeyBytes && kTagBytes >= crypto_generichash_BYTES_MIN &&
              kTagBytes <= crypto_generichash_BYTES_MAX);

std::int64_t read_be64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | p[i];
  return static_cast<std::int64_t>(v);
}

void write_be64(std::uint8_t* p, std::int64_t value) {
  auto v = static_cast<std::uint64_t>(value);
  for (int i = 7; i >= 0; --i, v >>= 8) p[i] = static_cast<std::uint8_t>(v & 0xff);
}

// a = BLAKE2b-256_K(len(channel) ‖ channel ‖ message[0, covered)).
void authenticator(const Key& key, std::string_view channel, const std::uint8_t* message, std::size_t covered,
                   std::uint8_t* tag) {
  crypto_generichash_state state;
  crypto_generichash_init(&state, key.bytes(), kKeyBytes, kTagBytes);
  const auto n = static_cast<std::uint32_t>(channel.size());
  const std::uint8_t length[4] = {static_cast<std::uint8_t>(n >> 24), static_cast<std::uint8_t>(n >> 16),
                                  static_cast<std::uint8_t>(n >> 8), static_cast<std::uint8_t>(n)};
  crypto_generichash_update(&state, length, sizeof length);
  crypto_generichash_update(&state, reinterpret_cast<const std::uint8_t*>(channel.data()), channel.size());
  crypto_generichash_update(&state, message, covered);
  crypto_generichash_final(&state, tag, kTagBytes);
  sodium_memzero(&state, sizeof state);  // it holds the keyed state
}

std::int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

Trailer read_trailer(const std::uint8_t* message, std::size_t size) {
  const std::uint8_t* t = message + size - kTrailerBytes;
  return {read_be64(t), read_be64(t + 8), read_be64(t + 16)};
}

Signer::Signer(std::shared_ptr<const KeyRing> keys, std::int64_t sender) : keys_(std::move(keys)), sender_(sender) {
  init_sodium();
}

std::int64_t Signer::next_counter() {
  const std::int64_t now = wall_us();
  std::int64_t last = last_.load();
  std::int64_t next = 0;
  do {
    next = std::max(last + 1, now);
  } while (!last_.compare_exchange_weak(last, next));
  return next;
}

void Signer::sign(std::string_view channel, std::span<std::uint8_t> message) {
  if (message.size() < kTrailerBytes) throw std::invalid_argument("a message shorter than its auth_t trailer");
  std::uint8_t* trailer = message.data() + message.size() - kTrailerBytes;
  if (!keys_) {
    std::fill(trailer, trailer + kTrailerBytes, std::uint8_t{0});
    return;
  }
  const Key& key = keys_->signing();
  write_be64(trailer, sender_);
  write_be64(trailer + 8, next_counter());
  write_be64(trailer + 16, key.id());
  authenticator(key, channel, message.data(), message.size() - kTagBytes, trailer + 24);
}

Verifier::Verifier(std::shared_ptr<const KeyRing> keys, std::int64_t max_age_us, bool replay_checks)
    : keys_(std::move(keys)), replay_checks_(replay_checks), window_(max_age_us) {
  init_sodium();
}

Verification Verifier::verify(std::string_view channel, const void* data, std::size_t size, std::int64_t now_us) {
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  if (!keys_) return {Verdict::kOk, 0, false, ""};  // an open bus: every sender is one, 0 (nothing is proven)
  if (bytes == nullptr || size < kTrailerBytes + 8) return {Verdict::kAuth, 0, false, "shorter than a signed message"};
  const Trailer t = read_trailer(bytes, size);
  if (t.key_id == 0) return {Verdict::kAuth, 0, false, "not signed (a sender on an open bus, or no cvo-slam sender)"};
  const Key* key = keys_->find(t.key_id);
  if (key == nullptr)
    return {Verdict::kAuth, 0, false,
            "signed with a key this receiver does not hold (another deployment's, or retired)"};
  std::uint8_t expected[kTagBytes];
  authenticator(*key, channel, bytes, size - kTagBytes, expected);
  if (crypto_verify_32(expected, bytes + size - kTagBytes) != 0)
    return {Verdict::kAuth, 0, false, "its authenticator does not match (changed after signing, or forged)"};
  if (!replay_checks_) return {Verdict::kOk, t.sender, true, ""};
  const WindowCheck fresh = window_.accept(t.sender, t.counter, now_us);
  return {fresh.accepted ? Verdict::kOk : Verdict::kReplay, t.sender, true, fresh.why};
}

Verification Verifier::verify(std::string_view channel, const void* data, std::size_t size) {
  return verify(channel, data, size, wall_us());
}

}  // namespace cvo::auth
