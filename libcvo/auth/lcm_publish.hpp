#pragma once
// Publishing onto LCM signed: every message a cvo-slam program puts on a channel goes through
// here (or signs its own encoding with Signer::sign before lcm::LCM::publish), so none leaves
// unsigned when a key is set.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "libcvo/auth/authenticator.hpp"

namespace cvo::auth {

/// Signs `bytes` (an encoded message) in place, then publishes them on `channel`.
inline int publish_bytes(::lcm::LCM& lcm, Signer& signer, const std::string& channel, std::span<std::uint8_t> bytes) {
  signer.sign(channel, bytes);
  return lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
}

/// Encodes an lcm-gen message (whose last field is auth_t), signs it and publishes it.
template <class Message>
int publish(::lcm::LCM& lcm, Signer& signer, const std::string& channel, const Message& message) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return publish_bytes(lcm, signer, channel, bytes);
}

}  // namespace cvo::auth
