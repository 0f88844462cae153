#include "daemon/backendd/map_schedule.hpp"

#include <utility>

namespace cvo::daemon::backendd {

bool MapSchedule::differs(std::int64_t session, const std::vector<std::uint8_t>& entry) const {
  const auto it = sent_.find(session);
  return it == sent_.end() || it->second.entry != entry;
}

void MapSchedule::sent(std::int64_t session, std::vector<std::uint8_t> entry, Clock::time_point now,
                       std::int64_t acknowledged) {
  sent_[session] = {std::move(entry), now, acknowledged};
}

void MapSchedule::seen(std::int64_t session, Clock::time_point now) { live_[session] = now; }

void MapSchedule::lost(std::int64_t session) { live_.erase(session); }

std::vector<std::int64_t> MapSchedule::resends_due(Clock::time_point now) {
  std::erase_if(live_, [&](const auto& entry) { return !live_at(entry.second, now); });
  std::vector<std::int64_t> due;
  for (const auto& [session, seen] : live_)
    if (const auto it = sent_.find(session); it != sent_.end() && now - it->second.at >= periods_.resend)
      due.push_back(session);
  return due;
}

std::vector<std::int64_t> MapSchedule::acknowledgements_due(const std::map<std::int64_t, std::int64_t>& held) const {
  std::vector<std::int64_t> due;
  for (const auto& [session, prefix] : held) {
    const auto it = sent_.find(session);
    if (prefix > (it == sent_.end() ? 0 : it->second.acknowledged)) due.push_back(session);
  }
  return due;
}

std::vector<std::int64_t> MapSchedule::live(const std::vector<std::int64_t>& sessions, Clock::time_point now) const {
  std::vector<std::int64_t> out;
  for (const std::int64_t session : sessions)
    if (const auto it = live_.find(session); it != live_.end() && live_at(it->second, now)) out.push_back(session);
  return out;
}

bool MapSchedule::map_due(Clock::time_point now, bool join) const {
  if (!map_changed_) return false;
  if (join || !map_sent_ || periods_.map.count() <= 0) return true;
  const auto since = now - *map_sent_;
  return since >= periods_.map || (loop_waiting_ && since >= periods_.loop);
}

void MapSchedule::map_sent(Clock::time_point now) {
  map_sent_ = now;
  map_changed_ = false;
  loop_waiting_ = false;
}

}  // namespace cvo::daemon::backendd
