#pragma once
// A daemon's end of the authenticated bus (libcvo/auth): the key ring of auth.key_file (none: an
// open bus), its sender id (auth/sender.hpp: stable across the daemon's restarts under systemd) and
// signer, shared by its threads, and a verifier for each receiving thread. Every publish goes through
// signer() (auth::publish), every received buffer through a verifier before it is decoded; a
// refusal is counted as BAD_AUTH or BAD_REPLAY and never decoded.
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "libcvo/auth/authenticator.hpp"
#include "libcvo/config/config.hpp"

namespace cvo::daemon {

class BusAuth {
 public:
  /// Reads the key file (throws auth::KeyFileError, which names it, when it cannot be used).
  BusAuth(const config::AuthParameters& settings, std::string_view program);

  [[nodiscard]] bool open() const { return keys_ == nullptr; }
  [[nodiscard]] auth::Signer& signer() { return signer_; }
  [[nodiscard]] std::int64_t sender() const { return signer_.sender(); }
  [[nodiscard]] const std::shared_ptr<const auth::KeyRing>& keys() const { return keys_; }
  [[nodiscard]] std::int64_t max_age_us() const { return max_age_us_; }
  /// For a thread that receives from `url`: replay checks, unless it is a file:// log (a
  /// recording read on purpose: authenticity only).
  [[nodiscard]] auth::Verifier verifier(std::string_view url) const;
  /// status_t's BUS_OPEN or BUS_AUTHENTICATED.
  [[nodiscard]] std::int8_t status_bus() const;
  /// What the daemon says once at start: the open bus, or the keys and the sender.
  [[nodiscard]] std::string describe() const;

 private:
  std::shared_ptr<const auth::KeyRing> keys_;
  std::int64_t max_age_us_;
  auth::Signer signer_;
};

/// status_t's BAD_AUTH or BAD_REPLAY for a refused verification.
int bad_kind(auth::Verdict verdict);

}  // namespace cvo::daemon
