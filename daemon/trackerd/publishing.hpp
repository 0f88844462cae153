#pragma once
// cvo-publish: Outbox -> LCM. Every event's CVO_POSE, CVO_KEYFRAME and CVO_LOCAL_GRAPH (encoded
// here, and kept as sent in the KeyframeHistory, so the back end's CVO_KEYFRAME_REQUEST is answered
// with the very bytes it missed; on a network in slices of one datagram on CVO_KEYFRAME_CHUNK,
// trackerd.keyframe_transport, libcvo/lcm/chunks.hpp), CVO_STATUS once a period and systemd's STATUS. In from LCM:
// CVO_MAP_CORRECTION and CVO_MAP (what the one decision of libcvo/lcm/map_decision.hpp trusts sets
// the running session's MapCorrection: a correction of another session is left at its decoding) and
// CVO_KEYFRAME_REQUEST. Runs until the tracker is done and the outbox is empty. With a key
// (auth.key_file) every message out is signed (a re-sent keyframe afresh: its counter is new), and
// every one in verified on its raw bytes first; a refusal counts BAD_AUTH or BAD_REPLAY.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/keyframe_request_t.hpp"

#include "daemon/common/latency_window.hpp"
#include "daemon/trackerd/delivery.hpp"
#include "daemon/trackerd/keyframe_history.hpp"
#include "daemon/trackerd/resend_budget.hpp"
#include "daemon/trackerd/shared.hpp"
#include "daemon/trackerd/slice_pacer.hpp"
#include "libcvo/auth/authenticator.hpp"
#include "libcvo/lcm/chunks.hpp"
#include "libcvo/lcm/map_decision.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"

namespace cvo::daemon::trackerd {

class Publishing {
 public:
  explicit Publishing(Shared& shared);
  void run();  // the thread's body

 private:
  void receive();
  /// The verified sender of an authentic, new buffer (0 on an open bus);
  /// nullopt, counted by kind, when not.
  std::optional<std::int64_t> authentic(const std::string& channel, const void* data, std::size_t size);
  void publish(const Event& event);
  void publish_keyframe(const Event& event);
  void send_record(const lcm::SlicedName& name, std::span<const std::uint8_t> bytes, std::uint32_t crc,
                   std::optional<lcm::SliceRange> slices);
  void send_slices();
  bool finished();
  void hand_over();
  std::vector<Spool::Entry> with_killed_graphs(const std::vector<Spool::Entry>& left);
  void send_unacknowledged();
  void answer_from_spool(const cvo_lcm::keyframe_request_t& request, const std::vector<KeyframeHistory::Wanted>& ranges,
                         const KeyframeHistory::Afford& afford);
  void remember_keyframe(std::int64_t id, const core::SE3& odometry_pose);
  void answer_request(const void* data, int size, std::int64_t requester);
  void publish_status(std::int8_t state_override);
  /// `channel`: CVO_MAP_CORRECTION or CVO_MAP; `sender`: its verified sender (auth_t; 0 on an open
  /// bus, unsigned).
  void apply_map(const std::string& channel, const void* data, int size, std::int64_t sender);
  void take_acknowledgement(const lcm::CorrectionDecision& d);
  KeyframeHistory& history();

  Shared& shared_;
  ::lcm::LCM lcm_;
  auth::Verifier verifier_;           // CVO_MAP_CORRECTION, CVO_MAP, CVO_KEYFRAME_REQUEST, before decoding
  std::vector<std::uint8_t> resend_;  // a message or slice as signed and sent
  const bool receives_;               // a file:// output is a log being written: nothing comes back on it
  const lcm::RgbdEncoding encoding_;
  const bool chunks_;                         // keyframes and local graphs in slices (trackerd.keyframe_transport)
  const std::string robot_;                   // trackerd.robot, named in every message
  std::unique_ptr<KeyframeHistory> history_;  // sized for the camera once the outbox is ready
  ResendBudget resend_budget_;                // what CVO_KEYFRAME_REQUESTs may make it send again
  std::string delivery_warning_;              // a spool that could not be opened (noted at start)
  Delivery delivery_;                         // acknowledgements, the spool, the linger (delivery.hpp)
  std::optional<Clock::time_point> done_at_;  // when the tracker was done and everything sent
  SlicePacer pacer_;                          // slices waiting to go out (slice_pacer.hpp)
  lcm::AppliedCorrection applied_;            // the last correction applied (either channel)
  // The running session's newest keyframes' odometry poses, for the check of a placement against
  // the session's loops (lcm::decide_map_correction); a ring of kOwnKeyframes.
  std::vector<lcm::OwnKeyframe> own_keyframes_;
  std::size_t own_next_ = 0;
  LatencyWindow latency_{1024};
  std::int64_t session_;  // of the last event published
  std::int64_t published_ = 0, published_at_last_status_ = 0, deadline_misses_ = 0, failed_at_last_status_ = 0;
  std::int64_t unsent_ = 0;             // keyframes that could not be encoded (lost before publication)
  std::int64_t outbox_lost_noted_ = 0;  // the outbox's lost() when last noted
  std::int64_t requests_answered_ = 0;
  Clock::time_point last_status_ = Clock::now(), last_frame_ = Clock::now();
};

}  // namespace cvo::daemon::trackerd
