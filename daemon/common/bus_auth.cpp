#include "daemon/common/bus_auth.hpp"

#include <cmath>

#include "cvo_lcm/status_t.hpp"
#include "libcvo/auth/sender.hpp"

namespace cvo::daemon {
namespace {

std::shared_ptr<const auth::KeyRing> read_keys(const std::string& file) {
  if (file == "none") return nullptr;
  return std::make_shared<const auth::KeyRing>(auth::read_key_file(file));
}

}  // namespace

BusAuth::BusAuth(const config::AuthParameters& settings, std::string_view program)
    : keys_(read_keys(settings.key_file)),
      max_age_us_(std::llround(settings.max_age_s * 1e6)),
      signer_(keys_, auth::this_process_sender_id(program)) {}

auth::Verifier BusAuth::verifier(std::string_view url) const {
  return auth::Verifier(keys_, max_age_us_, !url.starts_with("file://"));
}

std::int8_t BusAuth::status_bus() const {
  if (open()) return cvo_lcm::status_t::BUS_OPEN;
  return cvo_lcm::status_t::BUS_AUTHENTICATED;
}

std::string BusAuth::describe() const {
  if (open())
    return "warning: the bus is open (auth.key_file none): nothing is signed or verified, and any process that "
           "can reach the LCM group can speak for the daemons";
  std::string text = "bus authenticated: signing with key " + auth::key_name(keys_->signing().id());
  if (keys_->keys().size() > 1) text += ", accepting key " + auth::key_name(keys_->keys()[1].id()) + " too";
  return text + "; sender " + auth::key_name(sender());
}

int bad_kind(auth::Verdict verdict) {
  if (verdict == auth::Verdict::kReplay) return cvo_lcm::status_t::BAD_REPLAY;
  return cvo_lcm::status_t::BAD_AUTH;
}

}  // namespace cvo::daemon
