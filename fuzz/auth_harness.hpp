#pragma once
// The fuzzing key (not a secret: it only lets mutations of the seeds, which fuzz-seeds signs with
// it, reach past the authenticator into the replay window), and the verify step every LCM harness
// runs on its raw bytes first, exactly as the daemons do before decoding.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "libcvo/auth/authenticator.hpp"

namespace cvo::fuzz {

inline constexpr std::string_view kFuzzKeyHex = "f0f1f2f3f4f5f6f7f8f9fafbfcfdfeff000102030405060708090a0b0c0d0e0f";
inline constexpr std::string_view kFuzzChannel = "CVO_FUZZ";

inline std::shared_ptr<const auth::KeyRing> fuzz_keys() {
  std::vector<auth::Key> keys;
  keys.push_back(*auth::Key::from_hex(kFuzzKeyHex));
  return std::make_shared<const auth::KeyRing>(std::move(keys));
}

/// The verdict of a fresh receiver (no sender seen yet, freshness off: seeds are old) on the bytes.
inline auth::Verification verify_raw(const std::uint8_t* data, std::size_t size) {
  auth::Verifier verifier(fuzz_keys(), 30'000'000, false);
  return verifier.verify(kFuzzChannel, data, size);
}

}  // namespace cvo::fuzz
