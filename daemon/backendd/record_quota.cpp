#include "daemon/backendd/record_quota.hpp"

#include "libcvo/core/session.hpp"

namespace cvo::daemon::backendd {

std::string RecordQuota::refusal(std::int64_t session, std::int64_t sender) const {
  if (records_of_session(session) >= per_session_)
    return "session " + core::session_name(session) + " has " + std::to_string(per_session_) +
           " records stored already (backendd.max_records_per_session)";
  if (records_of_sender(sender) >= per_sender_)
    return "its sender has " + std::to_string(per_sender_) +
           " records stored already (backendd.max_records_per_sender)";
  return {};
}

void RecordQuota::count(std::int64_t session, std::int64_t sender) {
  ++sessions_[session];
  ++senders_[sender];
}

}  // namespace cvo::daemon::backendd
