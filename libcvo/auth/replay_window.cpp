#include "libcvo/auth/replay_window.hpp"

#include <algorithm>
#include <limits>

namespace cvo::auth {

ReplayWindow::ReplayWindow(std::int64_t max_age_us, std::size_t max_senders)
    : max_age_us_(max_age_us), max_senders_(std::max<std::size_t>(max_senders, 1)) {}

WindowCheck ReplayWindow::accept(std::int64_t sender, std::int64_t counter, std::int64_t now_us) {
  const bool too_old =
      now_us >= std::numeric_limits<std::int64_t>::min() + max_age_us_ && counter < now_us - max_age_us_;
  if (too_old) return {false, "older than auth.max_age_s (a recording, or a clock behind)"};
  auto it = senders_.find(sender);
  if (it == senders_.end()) {
    if (senders_.size() >= max_senders_) make_room(now_us);
    Sender fresh;
    fresh.recent[0] = counter;
    fresh.count = 1;
    fresh.highest = counter;
    fresh.heard_us = now_us;
    senders_.emplace(sender, fresh);
    return {true, ""};
  }
  Sender& s = it->second;
  const auto begin = s.recent.begin();
  const auto end = begin + static_cast<std::ptrdiff_t>(s.count);
  if (std::find(begin, end, counter) != end) return {false, "its counter was seen from this sender already"};
  const auto lowest = std::min_element(begin, end);
  if (counter < *lowest) return {false, "older than this sender's window of recent counters"};
  if (s.count < kWindow)
    s.recent[s.count++] = counter;
  else
    *lowest = counter;  // the lowest leaves the window; everything at or below it is refused from now on
  s.highest = std::max(s.highest, counter);
  s.heard_us = now_us;
  return {true, ""};
}

void ReplayWindow::make_room(std::int64_t now_us) {
  for (auto it = senders_.begin(); it != senders_.end();) {
    if (now_us >= std::numeric_limits<std::int64_t>::min() + max_age_us_ && it->second.highest < now_us - max_age_us_)
      it = senders_.erase(it);
    else
      ++it;
  }
  if (senders_.size() < max_senders_) return;
  const auto oldest = std::min_element(senders_.begin(), senders_.end(), [](const auto& a, const auto& b) {
    return a.second.heard_us < b.second.heard_us;
  });
  senders_.erase(oldest);
}

}  // namespace cvo::auth
