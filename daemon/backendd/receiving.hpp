#pragma once
// cvo-receive: nothing but decoding, checking and storing, so that no message waits on the back
// end's work and every accepted record is on disk before it is used.
//
//   LCM CVO_KEYFRAME / CVO_LOCAL_GRAPH (or their slices, CVO_KEYFRAME_CHUNK, put together first:
//   slice_intake.hpp) -> verified (auth_t), decoded once and checked -> the door (each keyframe
//   (session, id) and local graph once; a repeat with other content is refused:
//   libcvo/store/message_door.hpp), within the bounds per session and sender (record_quota.hpp)
//   -> appended to the keyframe store (durable before anything else happens) -> the work queue,
//   the decoded value (when it is full, only where the record lies in the store is queued, and
//   cvo-backend reads it back in its turn). What never came of a session (a gap in its keyframe
//   ids, a local graph or CVO_POSE naming an unknown keyframe) is asked for again on
//   CVO_KEYFRAME_REQUEST (keyframe_gaps.hpp). CVO_POSE and CVO_STATUS say which sessions are live.
//
// Before the thread starts, the store's records pass the same door (let_in), so a store written
// before the door, or a damaged one, cannot feed the mapper a repeat.
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cvo_lcm/keyframe_request_t.hpp"
#include "daemon/backendd/keyframe_gaps.hpp"
#include "daemon/backendd/record_quota.hpp"
#include "daemon/backendd/shared.hpp"
#include "daemon/backendd/slice_intake.hpp"
#include "libcvo/auth/authenticator.hpp"
#include "libcvo/store/keyframe_store.hpp"
#include "libcvo/store/message_door.hpp"

namespace lcm {
class LCM;
}

namespace cvo::daemon::backendd {

class Receiving {
 public:
  /// Notes the store's state (a new store on a full disk starts degraded).
  explicit Receiving(Shared& shared);

  /// The store's records (recovered, or a stored map's), through the door and onto the queue, in
  /// order; before the thread starts.
  void let_in(std::vector<store::StoredRecord> recovered);
  /// The thread's body: until Shared::stop; then what is in the socket is taken in too.
  void run();

 private:
  // A message through the door: its name, its content CRC, its value.
  struct Admitted {
    store::MessageKey key;
    std::uint32_t crc = 0;
    store::RecordValue value;
  };
  // The verified sender of an authentic, new buffer; nullopt, counted by kind, when not.
  std::optional<std::int64_t> authentic(auth::Verifier& verifier, const std::string& channel, const void* data,
                                        std::size_t size);
  template <class Message>
  std::optional<Message> decoded(const void* data, std::size_t size, const char* channel);
  // A whole CVO_KEYFRAME / CVO_LOCAL_GRAPH; `sender`: the verified sender (auth_t; 0 on an open
  // bus), for what is said of a refusal and for the bounds per sender.
  void receive(store::RecordKind kind, const std::uint8_t* data, std::size_t size, std::int64_t sender);
  std::optional<Admitted> admit(store::RecordKind kind, const std::uint8_t* data, std::size_t size,
                                std::int64_t sender);
  void store_and_queue(store::RecordKind kind, const std::uint8_t* data, std::size_t size, std::int64_t sender,
                       Admitted admitted);
  void refuse(std::size_t why, const std::string& detail);
  void receive_slice(const void* data, std::size_t size, std::int64_t sender);
  void count_strangers_dropped();
  void saw_pose(const void* data, std::size_t size);
  void saw_status(const void* data, std::size_t size);
  [[nodiscard]] cvo_lcm::keyframe_request_t request_message(const KeyframeGaps::Request& request) const;
  void ask_for_missing(::lcm::LCM& lcm, bool stopping);
  static GapPolicy gap_policy(const config::Config& config);
  void note_store_change();
  void retry_store(bool final);

  Shared& shared_;
  store::MessageDoor door_;  // filled from the store before the thread starts
  RecordQuota quota_;        // the same
  KeyframeGaps gaps_;        // the same
  SliceIntake slices_;       // messages that came in part (CVO_KEYFRAME_CHUNK)
  // Local graphs put together before their keyframe, let in after it.
  struct EarlyGraph {
    std::vector<std::uint8_t> message;
    std::int64_t sender = 0;
  };
  using KeyframeName = std::pair<std::int64_t, std::int64_t>;  // session, id
  static constexpr std::size_t kMaxEarlyGraphs = 64;
  std::map<KeyframeName, EarlyGraph> early_graphs_;
  // Whether the store was failing when last noted, and when held records were last retried.
  bool store_failing_ = false;
  Clock::time_point store_retried_{};
};

}  // namespace cvo::daemon::backendd
