#include "daemon/common/status.hpp"

#include <unistd.h>

#include "daemon/common/realtime.hpp"
#include "libcvo/core/units.hpp"

namespace cvo::daemon {

cvo_lcm::status_t status_message(lcm::ProcessStatus status, const Notes& notes) {
  status.utime = core::wall_utime();
  status.pid = static_cast<std::int32_t>(getpid());
  status.rss_bytes = resident_bytes();
  status.detail = notes.last();
  return lcm::status_message(status);
}

}  // namespace cvo::daemon
