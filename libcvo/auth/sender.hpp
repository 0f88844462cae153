#pragma once
// Who signed a message (auth_t.sender): an id per daemon, not per process start, so that a
// receiver's replay window and the per-sender bounds (issue 26's guards) follow one daemon across
// its restarts, while two daemons never share one.
//
//   sender = first 8 bytes of BLAKE2b-256("cvo-slam sender" ‖ machine id ‖ program ‖ instance)
//
// machine id: /etc/machine-id (one per host); program: "cvo-trackerd", "cvo-backendd", ...;
// instance: the systemd service unit it runs as ("cvo-trackerd.service", or
// "cvo-trackerd@front.service" for a second tracker on the robot), read from /proc/self/cgroup
// when this process is the unit's own (SYSTEMD_EXEC_PID, systemd >= 248).
// Two trackers on one robot are two units, so two senders; a restart keeps the unit, so the same
// sender, whose counter (a wall-clock time, authenticator.hpp) has moved on. Outside a service (a
// shell, a test) the instance is 64 random bits per start: processes started by hand never share
// an id, and each start is a sender of its own.
#include <cstdint>
#include <string>
#include <string_view>

namespace cvo::auth {

/// The formula above (never 0).
std::int64_t sender_id(std::string_view machine_id, std::string_view program, std::string_view instance);

/// The service unit named in a /proc/PID/cgroup text ("cvo-trackerd.service"), or "" when the
/// process is in none (a user session's scope, a container's root).
std::string service_unit(std::string_view cgroup_text);

/// This process's sender id as `program` (the machine id, its unit, or a random instance).
std::int64_t this_process_sender_id(std::string_view program);

}  // namespace cvo::auth
