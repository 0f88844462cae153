#pragma once
// CVO_STATUS as both daemons publish it: the daemon fills what it knows (lcm::ProcessStatus), and
// what every process reports alike (wall time, pid, resident memory, its last note) is filled
// here, then lcm::status_message makes the message.
#include "cvo_lcm/status_t.hpp"
#include "daemon/common/notes.hpp"
#include "libcvo/lcm/tracker_messages.hpp"

namespace cvo::daemon {

cvo_lcm::status_t status_message(lcm::ProcessStatus status, const Notes& notes);

}  // namespace cvo::daemon
