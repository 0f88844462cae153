#pragma once
// A frame source for cameras that may be unplugged and plugged back: it opens the source it wraps
// lazily, and when opening fails (SourceError) or the source reports kDisconnected it closes it
// and opens it again, with exponential back-off, for as long as it is read.
//
// read() never waits past its timeout for the back-off: when the next attempt is due later, it
// waits out the timeout and returns kTimeout; when it is due sooner, it waits for it, tries once
// and returns. Only an open attempt itself cannot be cut short (a device may take a moment to open). The first failure
// of each gap is returned as kDisconnected with the error; the reads that retry while the source stays away return
// kTimeout with the latest error as the message. kEndOfStream, kBadInput and frames pass through unchanged.
//
// Opened by spec, it also listens for libusb hot-plug arrivals of the cameras that spec's scheme
// opens (cameras.tsv): an arrival makes the next attempt due at once (a waiting read wakes for it)
// and restarts the back-off from its initial wait. The back-off keeps running as the backstop:
// where the platform has no hot-plug, and for devices whose ids the table does not know. Once
// open, describe() adds the camera's USB identity (ids, serial, speed, port) when libusb finds it.
//
// Each disconnection is a gap: when it began and ended and why, so the daemon can report it. The
// time before the first successful open is a gap too (the camera was not there at start).
// Like every source, one thread uses it.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "drivers/frame_source.hpp"
#include "drivers/open_source.hpp"
#include "drivers/usb_cameras.hpp"

namespace cvo::drivers {

struct Backoff {
  std::chrono::milliseconds initial{100};  // wait before the first retry after a failure
  std::chrono::milliseconds max{5000};     // the wait never grows beyond this
  double factor = 2.0;                     // each failed attempt multiplies the wait by this
};

struct SourceGap {
  std::chrono::steady_clock::time_point begin;
  std::optional<std::chrono::steady_clock::time_point> end;  // nullopt while still disconnected
  std::string reason;                                        // the error that began it
};

class ReconnectingSource final : public FrameSource {
 public:
  using Opener = std::function<std::unique_ptr<FrameSource>()>;  // throws SourceError

  /// Opens open_source(spec, options); watches for the spec's cameras arriving (see the top).
  ReconnectingSource(std::string spec, SourceOptions options, Backoff backoff = {});
  /// Opens whatever `open` returns; `name` stands for it in describe().
  ReconnectingSource(std::string name, Opener open, Backoff backoff = {});

  ~ReconnectingSource() override;
  ReconnectingSource(const ReconnectingSource&) = delete;
  ReconnectingSource& operator=(const ReconnectingSource&) = delete;

  ReadResult read(core::RgbdFrame& frame, std::chrono::milliseconds timeout) override;
  /// The camera was plugged in: the next open attempt is due now. Any thread may call it (the
  /// hot-plug handler does, from libusb's thread).
  void device_arrived();
  /// Whether libusb hot-plug events are being watched (false: back-off only).
  [[nodiscard]] bool watching_hotplug() const { return watch_ != nullptr; }
  /// Arrivals seen so far.
  [[nodiscard]] std::uint64_t arrivals() const { return arrivals_; }
  /// The open source's description, or the name and why it is disconnected.
  [[nodiscard]] std::string describe() const override;
  /// Of every source opened so far.
  [[nodiscard]] std::uint64_t lost_frames() const override;

  [[nodiscard]] bool connected() const { return source_ != nullptr; }
  [[nodiscard]] std::uint64_t open_attempts() const { return attempts_; }
  /// Successful opens after the source had been open before and went away.
  [[nodiscard]] std::uint64_t reconnects() const { return reconnects_; }
  /// All gaps so far, and the latest of them (at most kKeptGaps), oldest first.
  [[nodiscard]] std::uint64_t gap_count() const { return gap_count_; }
  [[nodiscard]] const std::deque<SourceGap>& gaps() const { return gaps_; }
  /// Total time disconnected, the ongoing gap included.
  [[nodiscard]] std::chrono::steady_clock::duration disconnected_time() const;

  static constexpr std::size_t kKeptGaps = 64;

 private:
  using Clock = std::chrono::steady_clock;

  ReconnectingSource(std::string name, Opener open, Backoff backoff, std::function<std::string()> identify);
  std::optional<ReadResult> try_open(Clock::time_point deadline);
  // Sleeps until `until`, or less when a device arrives; true when one did.
  bool wait_for_arrival(Clock::time_point until);
  ReadResult begin_gap_or_continue(const std::string& why, Clock::time_point now);

  const std::string name_;
  const Opener open_;
  const Backoff backoff_;
  const std::function<std::string()> identify_;  // the open camera's USB identity; empty: none
  std::string identity_;
  std::unique_ptr<FrameSource> source_;
  Clock::time_point next_attempt_{};  // the epoch: the first attempt is due at once
  Clock::duration wait_;              // before the attempt after the next failure
  std::string last_error_;
  std::uint64_t attempts_ = 0, reconnects_ = 0, gap_count_ = 0, lost_before_ = 0;
  bool was_connected_ = false;
  std::deque<SourceGap> gaps_;
  Clock::duration closed_gaps_time_{};
  std::mutex arrival_mutex_;
  std::condition_variable arrival_;
  bool arrived_ = false;  // guarded by arrival_mutex_
  std::atomic<std::uint64_t> arrivals_{0};
  std::unique_ptr<UsbArrivalWatch> watch_;  // last: stopped before the members it calls into go
};

}  // namespace cvo::drivers
