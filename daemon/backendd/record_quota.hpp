#pragma once
// How much one tracker session, and one sender, may make cvo-backendd store. Every new (session,
// id) a message names is written to the append-only store and replayed after each restart, so
// without a bound a faulty tracker (or, on an open bus, anyone) could grow the store without end:
// a made-up session per message, or a session that never stops. The bounds are generous for a
// robot (the defaults: backendd.max_records_per_session 200 000, a keyframe and its local graph a
// second for more than a day; backendd.max_records_per_sender 1 000 000) and hard: a record past
// either is refused (status_t::BAD_QUOTA) and noted, so an operator sees which session or sender
// hit it. The sender is the verified one of the message (0 on an open bus: all senders are one,
// and its bound is the store's). The stored records count too: the store is replayed through the
// same door before the receiver starts. Used by cvo-receive only.
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>

namespace cvo::daemon::backendd {

class RecordQuota {
 public:
  RecordQuota(std::size_t per_session, std::size_t per_sender) : per_session_(per_session), per_sender_(per_sender) {}

  /// "" when one more record of `session` from `sender` fits; otherwise which bound it passes.
  [[nodiscard]] std::string refusal(std::int64_t session, std::int64_t sender) const;
  /// A record of `session` from `sender` was stored.
  void count(std::int64_t session, std::int64_t sender);

  [[nodiscard]] std::size_t records_of_session(std::int64_t session) const { return find(sessions_, session); }
  [[nodiscard]] std::size_t records_of_sender(std::int64_t sender) const { return find(senders_, sender); }

 private:
  static std::size_t find(const std::map<std::int64_t, std::size_t>& m, std::int64_t key) {
    const auto it = m.find(key);
    return it == m.end() ? 0 : it->second;
  }
  std::size_t per_session_, per_sender_;
  std::map<std::int64_t, std::size_t> sessions_, senders_;  // records stored so far
};

}  // namespace cvo::daemon::backendd
