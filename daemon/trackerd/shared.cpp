#include "daemon/trackerd/shared.hpp"

#include <sys/random.h>

#include <cerrno>

#include "libcvo/config/module_parameters.hpp"
#include "libcvo/core/units.hpp"

namespace cvo::daemon::trackerd {

// Unique across restarts and machines. Should getrandom fail, the clock mixed into the previous id
// (splitmix64) still gives a new one.
std::int64_t new_session_id(std::uint64_t previous) {
  std::uint64_t id = 0;
  while (id == 0) {
    const auto n = getrandom(&id, sizeof id, 0);
    if (n == static_cast<ssize_t>(sizeof id) || (n < 0 && errno == EINTR)) continue;
    std::uint64_t z = previous += 0x9e3779b97f4a7c15ULL + static_cast<std::uint64_t>(core::steady_now_ns());
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    id = z ^ (z >> 31);
  }
  return static_cast<std::int64_t>(id);
}

Shared::Shared(config::Config c)
    : config(std::move(c)),
      parameters(config::keyframe_odometry_parameters(config)),
      bus(config.auth, "cvo-trackerd"),
      session(new_session_id()),
      ring(config.trackerd.ring_slots,
           config.trackerd.deterministic ? FrameRing::Overflow::kBlock : FrameRing::Overflow::kDropOldest) {}

void Shared::count_bad(int kind, const std::string& what, const std::string& why) {
  if (kind < 0 || kind >= cvo_lcm::status_t::NUM_BAD_KINDS) kind = cvo_lcm::status_t::BAD_CONTENT;
  const auto n = ++counters.bad_messages[kind];
  notes.note_limited(what, what + " #" + std::to_string(n) + ": " + why);
}

}  // namespace cvo::daemon::trackerd
