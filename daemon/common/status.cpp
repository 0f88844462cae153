#include "daemon/common/status.hpp"

#include <unistd.h>

#include "daemon/common/realtime.hpp"
#include "libcvo/config/config.hpp"
#include "libcvo/core/units.hpp"

namespace cvo::daemon {

cvo_lcm::status_t status_message(lcm::ProcessStatus status, const Notes& notes) {
  status.utime = core::wall_utime();
  status.pid = static_cast<std::int32_t>(getpid());
  status.rss_bytes = resident_bytes();
  status.detail = notes.last();
  return lcm::status_message(status);
}

std::string robot_name(std::string_view configured) {
  if (configured != config::kHostName) return std::string(configured);
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0 || host[0] == 0) return "localhost";
  return host;
}

}  // namespace cvo::daemon
