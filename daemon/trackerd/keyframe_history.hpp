#pragma once
// cvo-trackerd's keyframe history: the last N keyframes it published, each with its local graph once
// that is published, kept exactly as sent (the encoded CVO_KEYFRAME and CVO_LOCAL_GRAPH messages,
// with their content CRC), so that a back end that missed one, or some of its slices
// (CVO_KEYFRAME_CHUNK, libcvo/lcm/chunks.hpp), can have it again (CVO_KEYFRAME_REQUEST,
// proto/keyframe_request_t.lcm). A re-send is byte-identical: should the first copy have arrived
// after all, the back end's door takes the second as a repeat, not as a conflict.
//
// All storage is allocated at construction: N slots, each sized for the largest keyframe and local
// graph the tracker can publish; the newest keyframe takes the oldest slot. A message larger than
// its slot is not kept (and is counted lost if asked for). Used by the publisher thread only.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <utility>
#include <vector>

#include "libcvo/lcm/chunks.hpp"

namespace cvo::daemon::trackerd {

class KeyframeHistory {
 public:
  /// `keyframes` slots (0: none kept), each of keyframe_bytes for a keyframe and graph_bytes for
  /// its local graph.
  KeyframeHistory(std::size_t keyframes, std::size_t keyframe_bytes, std::size_t graph_bytes);

  /// Keyframe `id` of `session` was made by this tracker, published or not: requests for ids up
  /// to the newest made are this tracker's to answer; a higher one names no keyframe.
  void made(std::int64_t session, std::int64_t id);
  /// Keyframe `id` never went out (dropped before publication, counted where it was dropped): a
  /// request for it is answered as lost without being counted a second time.
  void never_sent(std::int64_t session, std::int64_t id);

  /// Keeps the message of keyframe (session, id), whose content CRC is `crc` (lcm::content_crc), in
  /// the oldest slot; false when it is larger than a slot (not kept).
  bool keep_keyframe(std::int64_t session, std::int64_t id, std::span<const std::uint8_t> message, std::uint32_t crc);
  /// Keeps the message of the local graph of keyframe (session, id) with that keyframe; false when
  /// the keyframe is not held (any more) or the graph is larger than its place.
  bool keep_graph(std::int64_t session, std::int64_t id, std::span<const std::uint8_t> message, std::uint32_t crc);

  struct Message {
    std::span<const std::uint8_t> bytes;  // empty: none (a local graph not published yet, or not kept)
    std::uint32_t crc = 0;
  };
  struct Held {
    Message keyframe, graph;
  };
  [[nodiscard]] std::optional<Held> find(std::int64_t session, std::int64_t id) const;

  /// Slices a request asks for of one message (keyframe_request_t's ranges).
  struct Wanted {
    std::int64_t id = 0;
    bool graph = false;  // the keyframe's local graph, else the keyframe
    lcm::SliceRange slices;
  };
  /// What goes out again: keyframe `id`'s message (or its local graph's), all of it or some slices.
  struct Resend {
    std::int64_t id = 0;
    bool graph = false;
    Message message;
    std::optional<lcm::SliceRange> slices;  // nullopt: all of it
  };
  struct Answer {
    bool ours = false;                // the session is one of this tracker's
    std::vector<std::int64_t> sent;   // sent again (all of it, or slices)
    std::vector<std::int64_t> lost;   // no longer held
    std::vector<std::int64_t> never;  // never made in that session: a bad request
    std::vector<std::int64_t> over;   // held, not sent: over the re-send budget (asked again, sent later)
  };
  using Send = std::function<void(const Resend&)>;
  using Afford = std::function<bool(std::size_t bytes)>;  // may `bytes` go out again?
  /// A request for keyframes `ids` of `session`, and for slices `ranges` of messages of its
  /// keyframes: nothing when the session is not this tracker's (another tracker answers). Else
  /// each distinct id still held is sent again through `send`, its keyframe then its local graph
  /// when it has one, and the slices of each range that its message has; an id made but no longer
  /// held is counted lost, once however often it is asked for. What `afford` (when given) refuses
  /// is not sent (Answer::over).
  Answer answer(std::int64_t session, std::span<const std::int64_t> ids, std::span<const Wanted> ranges,
                const Send& send, const Afford& afford = nullptr);

  [[nodiscard]] std::int64_t resent() const { return resent_; }  // keyframes sent again
  [[nodiscard]] std::int64_t lost() const { return lost_; }      // asked for, no longer held, each once
  [[nodiscard]] std::size_t capacity() const { return slots_.size(); }
  /// Makes every slot hold keyframes of up to `keyframe_bytes` (a camera of a larger size); what
  /// is held and counted stays. Allocates: the publisher calls it, not the tracking thread.
  void reserve_keyframe_bytes(std::size_t keyframe_bytes);

 private:
  struct Slot {
    bool used = false;
    std::int64_t session = 0, id = 0;
    std::vector<std::uint8_t> keyframe, graph;  // capacity reserved once; size: the message
    std::uint32_t keyframe_crc = 0, graph_crc = 0;
  };
  // Whether `id` of `session` is held; else counted lost (or never made) in `answer`.
  [[nodiscard]] std::optional<Held> held_or_noted(std::int64_t session, std::int64_t newest, std::int64_t id,
                                                  Answer& answer);
  [[nodiscard]] std::size_t index_of(std::int64_t session, std::int64_t id) const;  // slots_.size(): none

  std::vector<Slot> slots_;
  std::size_t keyframe_bytes_, graph_bytes_;              // each slot's room
  std::size_t next_ = 0;                                  // the oldest slot, taken by the next keyframe
  std::map<std::int64_t, std::int64_t> newest_;           // this tracker's sessions: their newest keyframe id
  std::set<std::pair<std::int64_t, std::int64_t>> gone_;  // answered lost or never sent: counted already
  std::int64_t resent_ = 0, lost_ = 0;
};

}  // namespace cvo::daemon::trackerd
