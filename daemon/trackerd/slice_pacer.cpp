#include "daemon/trackerd/slice_pacer.hpp"

#include <utility>

namespace cvo::daemon::trackerd {

void SlicePacer::add(const lcm::SlicedName& name, std::shared_ptr<const std::vector<std::uint8_t>> message,
                     std::uint32_t crc, lcm::SliceRange range) {
  const lcm::SliceRange r = lcm::clamp(range, message->size());
  if (r.count == 0) return;
  jobs_.push_back({name, std::move(message), crc, r.first, r.first + r.count});
}

std::size_t SlicePacer::send_due(Clock::time_point now, const Send& send) {
  if (jobs_.empty() || now - last_burst_ < kTick) return 0;
  last_burst_ = now;
  std::size_t sent = 0;
  while (sent < kBurst && !jobs_.empty()) {
    Job& job = jobs_.front();
    send(lcm::slice(*job.message, job.name, job.crc, job.next));
    ++sent;
    if (++job.next == job.end) jobs_.pop_front();
  }
  return sent;
}

std::size_t SlicePacer::waiting() const {
  std::size_t n = 0;
  for (const Job& job : jobs_) n += static_cast<std::size_t>(job.end - job.next);
  return n;
}

}  // namespace cvo::daemon::trackerd
