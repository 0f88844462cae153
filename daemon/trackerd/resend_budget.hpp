#pragma once
// How much cvo-trackerd may send again for CVO_KEYFRAME_REQUESTs: without a bound, a request of
// 190 bytes re-sends up to 16 keyframes of ~260 kB each, so a flood of requests (a faulty back end,
// anyone on an open bus) makes the tracker fill the network — measured 22 000 times amplified.
//
// Token buckets of bytes, each refilled at `bytes_per_s` up to one second's worth (a burst the size
// of the rate): one per requester (the verified sender of the request; 0 on an open bus, where
// all requesters are one) and one per session asked for. A keyframe goes out again only when both
// of its buckets hold its bytes (or are full: a message larger than a second's worth is not kept
// out for good), which both then pay: the re-sent bytes of a session, and of a requester, are at
// most bytes_per_s · t + max(bytes_per_s, one message) over any t seconds. A back end that lost a
// few keyframes to a full socket buffer needs far less; one that asks for more is served over
// the following seconds, as it asks again. Tables hold kTracked requesters and sessions, the least
// recently seen forgotten first (a forgotten one starts with a full bucket, which the bound above
// still covers per table entry). Used by the publisher thread only.
#include <array>
#include <cstddef>
#include <cstdint>

namespace cvo::daemon::trackerd {

class ResendBudget {
 public:
  explicit ResendBudget(double bytes_per_s) : rate_(bytes_per_s) {}

  /// May `bytes` be sent again now (`now_s`, a steady clock in seconds) for `requester`, of
  /// `session`? When yes, both buckets pay them.
  bool take(std::int64_t requester, std::int64_t session, std::size_t bytes, double now_s);

  [[nodiscard]] std::int64_t refused() const { return refused_; }  // re-sends refused so far

 private:
  static constexpr std::size_t kTracked = 16;
  struct Bucket {
    std::int64_t key = 0;
    bool used = false;
    double tokens = 0, at_s = 0;  // bytes held at at_s (also when last seen)
  };
  using Table = std::array<Bucket, kTracked>;
  Bucket& bucket(Table& table, std::int64_t key, double now_s) const;

  double rate_;
  Table requesters_{}, sessions_{};
  std::int64_t refused_ = 0;
};

}  // namespace cvo::daemon::trackerd
