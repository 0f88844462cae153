#include "daemon/backendd/held_prefix.hpp"

namespace cvo::daemon::backendd {

void HeldPrefix::held(std::int64_t session, std::int64_t id, bool graph) {
  const std::lock_guard lock(mutex_);
  Session& s = sessions_[session];
  if (id < s.prefix) return;
  s.above.emplace(id, graph);
  while (s.above.contains({s.prefix, false}) && s.above.contains({s.prefix, true})) {
    s.above.erase({s.prefix, false});
    s.above.erase({s.prefix, true});
    ++s.prefix;
    grown_.insert(session);
  }
}

void HeldPrefix::merged(std::int64_t session, std::int64_t id) {
  held(session, id, false);
  held(session, id, true);
}

std::int64_t HeldPrefix::acknowledged(std::int64_t session) const {
  const std::lock_guard lock(mutex_);
  const auto it = sessions_.find(session);
  return it == sessions_.end() ? 0 : it->second.prefix;
}

std::map<std::int64_t, std::int64_t> HeldPrefix::take_grown() {
  const std::lock_guard lock(mutex_);
  std::map<std::int64_t, std::int64_t> out;
  for (const std::int64_t session : grown_) out.emplace(session, sessions_.at(session).prefix);
  grown_.clear();
  return out;
}

}  // namespace cvo::daemon::backendd
