#include "daemon/backendd/shared.hpp"

#include <limits>
#include <utility>

namespace cvo::daemon::backendd {

std::string publish_url(const config::BackenddParameters& b) {
  return b.publish_url == "lcm_url" ? b.lcm_url : b.publish_url;
}

std::string keyframe_name(core::SessionId session, std::int64_t id) {
  return describe(store::MessageKey{store::RecordKind::kKeyframe, session, id});
}

Shared::Shared(config::Config c)
    : config(std::move(c)), bus(config.auth, "cvo-backendd"), queue(config.backendd.queue_max) {}

double Shared::stop_time_left() const {
  const Clock::time_point deadline{Clock::duration{stop_deadline.load()}};
  if (deadline == Clock::time_point::max()) return std::numeric_limits<double>::infinity();
  return std::chrono::duration<double>(deadline - Clock::now()).count();
}

}  // namespace cvo::daemon::backendd
