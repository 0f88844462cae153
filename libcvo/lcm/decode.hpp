#pragma once
// Decoding of cvo_lcm messages from bytes that came off the network or out of a file, trusting
// nothing: every failure is a nullopt and a message, never an exception, a crash or a huge
// allocation.
//
// Checks, in order: at least 8 bytes (LCM's encoding starts with the type's 64-bit fingerprint, a
// hash of its definition and of the types it embeds); the fingerprint (another type, or another
// schema of this one); the element counts against the buffer (wire_layout.hpp); lcm-gen's decoder
// (truncated body); no trailing bytes (an oversized buffer is not this message); and, for types
// with a `version` field, version == SCHEMA_VERSION. Which check failed is also reported as a
// DecodeFailure, so a receiver can count refusals by kind (CVO_STATUS's bad_messages).
#include <cstdint>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include "libcvo/core/bad_kind.hpp"
#include "libcvo/lcm/wire_layout.hpp"

namespace cvo::lcm {

/// Which check refused a buffer (kTooShort, kFingerprint, kBody or kVersion), and why a message
/// that decoded cannot be used (the from_message conversions: kContent, kNotFinite, ...): both are
/// the one list of refusal kinds, core::BadKind, whose values are CVO_STATUS's bad_messages indices.
using DecodeFailure = core::BadKind;
using ContentFailure = core::BadKind;

namespace detail {
std::string hex64(std::uint64_t v);
inline void set_error(std::string* error, const char* type, const std::string& what) {
  if (error != nullptr) *error = std::string("cvo_lcm.") + type + ": " + what;
}
inline void set_failure(DecodeFailure* out, DecodeFailure failure) {
  if (out != nullptr) *out = failure;
}
}  // namespace detail

/// T is an lcm-gen type of package cvo_lcm. On failure returns nullopt and, when error is not
/// null, says why ("cvo_lcm.pose_t: wrong fingerprint ..."); when failure is not null, which check
/// refused the buffer (left untouched on success).
template <class T>
std::optional<T> decode(const void* data, int size, std::string* error, DecodeFailure* failure = nullptr) {
  const char* type = T::getTypeName();
  if (data == nullptr || size < 8) {
    detail::set_error(
        error, type,
        "buffer of " + std::to_string(data == nullptr ? 0 : size) + " bytes is shorter than the 8-byte fingerprint");
    detail::set_failure(failure, DecodeFailure::kTooShort);
    return std::nullopt;
  }
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  std::uint64_t fingerprint = 0;
  for (int i = 0; i < 8; ++i) fingerprint = (fingerprint << 8) | bytes[i];
  const auto expected = static_cast<std::uint64_t>(T::getHash());
  if (fingerprint != expected) {
    detail::set_error(error, type,
                      "wrong fingerprint " + detail::hex64(fingerprint) + " (expected " + detail::hex64(expected) +
                          "): another message type or another schema version");
    detail::set_failure(failure, DecodeFailure::kFingerprint);
    return std::nullopt;
  }
  if (const std::string bad = check_counts(wire_layout(type), bytes + 8, size - 8); !bad.empty()) {
    detail::set_error(error, type, bad);
    detail::set_failure(failure, DecodeFailure::kBody);
    return std::nullopt;
  }
  T message;
  int used = -1;
  try {
    used = message.decode(data, 0, size);
  } catch (const std::exception& e) {  // lcm-gen strings: a negative length throws std::length_error
    detail::set_error(error, type, std::string("corrupt body (") + e.what() + ")");
    detail::set_failure(failure, DecodeFailure::kBody);
    return std::nullopt;
  }
  if (used < 0) {
    detail::set_error(error, type, "truncated or corrupt body (" + std::to_string(size) + " bytes)");
    detail::set_failure(failure, DecodeFailure::kBody);
    return std::nullopt;
  }
  if (used != size) {
    detail::set_error(
        error, type, std::to_string(size - used) + " trailing bytes after a " + std::to_string(used) + "-byte message");
    detail::set_failure(failure, DecodeFailure::kBody);
    return std::nullopt;
  }
  if constexpr (requires {
                  message.version;
                  T::SCHEMA_VERSION;
                }) {
    if (message.version != T::SCHEMA_VERSION) {
      detail::set_error(error, type,
                        "schema version " + std::to_string(message.version) + ", this build reads version " +
                            std::to_string(T::SCHEMA_VERSION));
      detail::set_failure(failure, DecodeFailure::kVersion);
      return std::nullopt;
    }
  }
  return message;
}

/// The message's encoding (fingerprint included), as lcm::LCM::publish and lcm::LogFile send it.
template <class T>
std::vector<std::uint8_t> encode(const T& message) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

}  // namespace cvo::lcm
