#pragma once
// What cvo-backendd acknowledges of each tracker session (map_correction_t.acknowledged, issue 28):
// the length of the prefix of keyframe ids whose keyframe and local graph are both in the store
// (durable), or merged into another keyframe (the merge record stands for them). A tracker keeps
// what is not acknowledged, in its spool and at its exit, and sends it again.
//
// cvo-receive marks records as they are stored (and as the store is read back at start);
// cvo-backend reads the prefix when it publishes a session's correction, and takes the sessions
// whose prefix grew, to acknowledge them at once (map_schedule.hpp). Thread-safe.
#include <cstdint>
#include <map>
#include <mutex>
#include <set>
#include <utility>

namespace cvo::daemon::backendd {

class HeldPrefix {
 public:
  /// The keyframe (graph false) or local graph (graph true) of keyframe `id` of `session` is held.
  void held(std::int64_t session, std::int64_t id, bool graph);
  /// Both, for a keyframe merged into another (its merge record stands for it and its graph).
  void merged(std::int64_t session, std::int64_t id);
  /// Keyframes 0 .. acknowledged(session) - 1 are all held, each with its local graph.
  [[nodiscard]] std::int64_t acknowledged(std::int64_t session) const;
  /// The sessions whose prefix grew since the last call, each with its prefix now.
  [[nodiscard]] std::map<std::int64_t, std::int64_t> take_grown();

 private:
  struct Session {
    std::int64_t prefix = 0;
    std::set<std::pair<std::int64_t, bool>> above;  // held past the prefix: (id, graph)
  };
  mutable std::mutex mutex_;
  std::map<std::int64_t, Session> sessions_;
  std::set<std::int64_t> grown_;  // since take_grown(): at most one entry a session
};

}  // namespace cvo::daemon::backendd
