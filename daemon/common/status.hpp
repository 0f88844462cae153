#pragma once
// CVO_STATUS as both daemons publish it: the daemon fills what it knows (lcm::ProcessStatus), and
// what every process reports alike (wall time, pid, resident memory, its last note) is filled
// here, then lcm::status_message makes the message.
#include <string>
#include <string_view>

#include "cvo_lcm/status_t.hpp"
#include "daemon/common/notes.hpp"
#include "libcvo/lcm/tracker_messages.hpp"

namespace cvo::daemon {

cvo_lcm::status_t status_message(lcm::ProcessStatus status, const Notes& notes);

/// The robot a process speaks for: `configured` (trackerd.robot), or this machine's host name when
/// that is config::kHostName (or "localhost" when the host has none).
std::string robot_name(std::string_view configured);

}  // namespace cvo::daemon
