#include "daemon/trackerd/acknowledgements.hpp"

#include <algorithm>

namespace cvo::daemon::trackerd {

void Acknowledgements::ready(std::int64_t session, std::int64_t id, Clock::time_point now) {
  Session& s = sessions_[session];
  s.newest = std::max(s.newest, id);
  if (id >= s.prefix) s.waiting.try_emplace(id, Waiting{now + kFirstWait, 0});
}

void Acknowledgements::acknowledged(std::int64_t session, std::int64_t prefix, Clock::time_point now) {
  const auto it = sessions_.find(session);
  if (it == sessions_.end()) return;  // not one of ours
  Session& s = it->second;
  s.prefix = prefix;
  s.heard = now;
  s.ever_heard = true;
  s.waiting.erase(s.waiting.begin(), s.waiting.lower_bound(prefix));
}

std::vector<std::int64_t> Acknowledgements::due(std::int64_t session, Clock::time_point now, std::size_t max) {
  std::vector<std::int64_t> ids;
  const auto it = sessions_.find(session);
  if (it == sessions_.end()) return ids;
  Session& s = it->second;
  if (!s.ever_heard || now - s.heard > kAlive) return ids;  // nobody to send to: waits for the back end
  for (auto& [id, w] : s.waiting) {
    if (ids.size() >= max) break;
    if (id < s.prefix || w.next > now) continue;
    ids.push_back(id);
    ++w.sent;
    w.next = now + std::min<Clock::duration>(kFirstWait * (std::int64_t{1} << std::min(w.sent, 10)), kMaxWait);
  }
  return ids;
}

std::vector<std::int64_t> Acknowledgements::unacknowledged(std::int64_t session) const {
  std::vector<std::int64_t> ids;
  if (const auto it = sessions_.find(session); it != sessions_.end())
    for (const auto& [id, w] : it->second.waiting)
      if (id >= it->second.prefix) ids.push_back(id);
  return ids;
}

std::int64_t Acknowledgements::prefix(std::int64_t session) const {
  const auto it = sessions_.find(session);
  return it == sessions_.end() ? 0 : it->second.prefix;
}

std::optional<std::int64_t> Acknowledgements::newest(std::int64_t session) const {
  const auto it = sessions_.find(session);
  if (it == sessions_.end()) return std::nullopt;
  return it->second.newest;
}

std::vector<std::int64_t> Acknowledgements::sessions() const {
  std::vector<std::int64_t> out;
  for (const auto& [session, s] : sessions_) out.push_back(session);
  return out;
}

}  // namespace cvo::daemon::trackerd
