#include "daemon/trackerd/resend_budget.hpp"

#include <algorithm>

namespace cvo::daemon::trackerd {

ResendBudget::Bucket& ResendBudget::bucket(Table& table, std::int64_t key, double now_s) const {
  Bucket* oldest = table.data();
  for (Bucket& b : table) {
    if (b.used && b.key == key) {
      b.tokens = std::min(rate_, b.tokens + rate_ * std::max(0.0, now_s - b.at_s));
      b.at_s = now_s;
      return b;
    }
    if (!b.used || (oldest->used && b.at_s < oldest->at_s)) oldest = &b;
  }
  *oldest = {key, true, rate_, now_s};  // new, or in place of the least recently seen
  return *oldest;
}

bool ResendBudget::take(std::int64_t requester, std::int64_t session, std::size_t bytes, double now_s) {
  Bucket& r = bucket(requesters_, requester, now_s);
  Bucket& s = bucket(sessions_, session, now_s);
  const auto cost = static_cast<double>(bytes);
  // A full bucket pays for any one message, going into debt (a keyframe larger than a second's
  // worth still goes out, once its buckets have refilled).
  const auto affords = [&](const Bucket& b) { return b.tokens >= cost || b.tokens >= rate_; };
  if (!affords(r) || !affords(s)) {
    ++refused_;
    return false;
  }
  r.tokens -= cost;
  s.tokens -= cost;
  return true;
}

}  // namespace cvo::daemon::trackerd
