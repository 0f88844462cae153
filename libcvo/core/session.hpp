#pragma once
// A session: one tracker run in one odometry frame (cvo-trackerd starts one per start, camera
// re-initialisation or camera change; cvo-run --mode slam one per folder). Its id is carried by
// every message of the run (CVO_POSE, CVO_KEYFRAME, CVO_LOCAL_GRAPH, CVO_MAP, CVO_STATUS) and keys
// the back end's map; 0 is never a session. In core because the tracker, the wire format and the
// back end all name sessions, and the tracker must not link the back end to do so.
#include <cstdint>
#include <string>
#include <string_view>

namespace cvo::core {

using SessionId = std::int64_t;

/// How logs and messages name a session: its 64 bits in hex, "0x0123456789abcdef".
std::string session_name(SessionId session);

/// A robot's name, as trackerd.robot and every tracker message carry it: 1 to 64 letters, digits,
/// '.', '-' or '_' (a host name's characters, RFC 1123, and '_'), since it names the robot in
/// messages, logs and cvo-log's output, where spaces and control characters would not survive.
bool is_robot_name(std::string_view name);
inline constexpr std::string_view kRobotNameRule = "1 to 64 letters, digits, '.', '-' or '_'";  // for messages
/// "" for a robot name, else why not (its length, not its bytes: they may be anything).
std::string robot_name_error(std::string_view name);

/// Where a session stands in the map (CVO_POSE, CVO_MAP): not placed yet, placed (its map poses
/// are map poses), or its odometry failed (a new session follows; this one is over).
enum class LocalizationState : std::int8_t { kLocalizing = 0, kLocalized = 1, kLost = 2 };
const char* to_string(LocalizationState state);  // "localizing", "localized", "lost"

}  // namespace cvo::core
