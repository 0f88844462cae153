#pragma once
// A session: one tracker run in one odometry frame (cvo-trackerd starts one per start, camera
// re-initialisation or camera change; cvo-run --mode slam one per folder). Its id is carried by
// every message of the run (CVO_POSE, CVO_KEYFRAME, CVO_LOCAL_GRAPH, CVO_MAP, CVO_STATUS) and keys
// the back end's map; 0 is never a session. In core because the tracker, the wire format and the
// back end all name sessions, and the tracker must not link the back end to do so.
#include <cstdint>
#include <string>

namespace cvo::core {

using SessionId = std::int64_t;

/// How logs and messages name a session: its 64 bits in hex, "0x0123456789abcdef".
std::string session_name(SessionId session);

}  // namespace cvo::core
