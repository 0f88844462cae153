#pragma once
// A receiver's memory of what each sender sent, so that each authentic message is taken once.
//
// Counters are strictly increasing per sender (authenticator.hpp). Per sender the window keeps the
// kWindow most recent counters it accepted; counter c is a replay when it is one of them, or lower
// than the lowest of them (nothing below that is remembered, so nothing below it is taken: before
// the window is full its lowest is the first counter seen). That is a window of 64 messages, not of
// 64 counter values: counters are microsecond times, and two messages a few milliseconds apart may
// arrive swapped (two threads of a sender, UDP). A counter older than the receiver's clock by more
// than max_age is refused too, seen or not: a recording played to a receiver that never saw its
// sender, or that restarted since. A sender whose newest counter is older than max_age needs no
// state (all its older counters are refused by age), so the table is bounded: past max_senders, such
// senders are forgotten first, else the least recently heard.
#include <array>
#include <cstddef>
#include <cstdint>
#include <unordered_map>

namespace cvo::auth {

struct WindowCheck {
  bool accepted = false;
  const char* why = "";  // why not (a static text)
};

class ReplayWindow {
 public:
  static constexpr std::size_t kWindow = 64;
  static constexpr std::size_t kMaxSenders = 256;

  explicit ReplayWindow(std::int64_t max_age_us, std::size_t max_senders = kMaxSenders);

  /// Whether `counter` from `sender` is new, at the receiver's wall time now_us (µs since 1970);
  /// an accepted one is remembered.
  WindowCheck accept(std::int64_t sender, std::int64_t counter, std::int64_t now_us);

  [[nodiscard]] std::size_t senders() const { return senders_.size(); }

 private:
  struct Sender {
    std::array<std::int64_t, kWindow> recent{};  // accepted counters, unordered
    std::size_t count = 0;
    std::int64_t highest = 0;
    std::int64_t heard_us = 0;  // receiver time of the last accepted message
  };
  void make_room(std::int64_t now_us);

  std::int64_t max_age_us_;
  std::size_t max_senders_;
  std::unordered_map<std::int64_t, Sender> senders_;
};

}  // namespace cvo::auth
