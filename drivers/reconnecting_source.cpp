#include "drivers/reconnecting_source.hpp"

#include <algorithm>
#include <utility>

#include "drivers/read_result.hpp"

namespace cvo::drivers {

namespace {

// The ids of the cameras a spec's scheme opens; none when the table cannot be read (then only the
// back-off re-opens).
std::vector<UsbIds> camera_ids(const std::string& spec) {
  try {
    return CameraTable::load().ids_for_spec(spec);
  } catch (const std::exception&) {
    return {};
  }
}

}  // namespace

ReconnectingSource::ReconnectingSource(std::string spec, SourceOptions options, Backoff backoff)
    : ReconnectingSource(
          spec, [spec, options = std::move(options)] { return open_source(spec, options); }, backoff,
          [spec] { return usb_identity(spec); }) {
  watch_ = UsbArrivalWatch::start(camera_ids(spec), [this] { device_arrived(); });
}

ReconnectingSource::ReconnectingSource(std::string name, Opener open, Backoff backoff)
    : ReconnectingSource(std::move(name), std::move(open), backoff, {}) {}

ReconnectingSource::ReconnectingSource(std::string name, Opener open, Backoff backoff,
                                       std::function<std::string()> identify)
    : name_(std::move(name)),
      open_(std::move(open)),
      backoff_(backoff),
      identify_(std::move(identify)),
      wait_(backoff.initial) {}

ReconnectingSource::~ReconnectingSource() { watch_.reset(); }  // no arrival after this

void ReconnectingSource::device_arrived() {
  ++arrivals_;
  {
    const std::lock_guard lock(arrival_mutex_);
    arrived_ = true;
  }
  arrival_.notify_all();
}

bool ReconnectingSource::wait_for_arrival(Clock::time_point until) {
  std::unique_lock lock(arrival_mutex_);
  arrival_.wait_until(lock, until, [this] { return arrived_; });
  return std::exchange(arrived_, false);
}

ReadResult ReconnectingSource::read(core::RgbdFrame& frame, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  if (!source_) {
    if (auto not_open = try_open(deadline)) return *not_open;
  }
  const auto left =
      std::max(std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()), std::chrono::milliseconds(0));
  ReadResult outcome = source_->read(frame, left);
  if (outcome.status == ReadStatus::kDisconnected) {
    lost_before_ += source_->lost_frames();
    source_.reset();
    begin_gap_or_continue(outcome.message, Clock::now());
  }
  return outcome;
}

// What read() returns when the source is still not open; nullopt once it is.
std::optional<ReadResult> ReconnectingSource::try_open(Clock::time_point deadline) {
  if (wait_for_arrival(std::min(next_attempt_, deadline))) {
    wait_ = backoff_.initial;             // plugged in: try now, and soon again if it is not ready yet
  } else if (next_attempt_ > deadline) {  // not due within this read
    return result(ReadStatus::kTimeout, last_error_);
  }
  ++attempts_;
  try {
    source_ = open_();
  } catch (const SourceError& e) {
    return begin_gap_or_continue(e.what(), Clock::now());
  }
  identity_ = identify_ ? identify_() : std::string();
  if (!gaps_.empty() && !gaps_.back().end) {
    const auto now = Clock::now();
    gaps_.back().end = now;
    closed_gaps_time_ += now - gaps_.back().begin;
  }
  if (was_connected_) ++reconnects_;
  was_connected_ = true;
  wait_ = backoff_.initial;
  return std::nullopt;
}

// After a failed open or a lost source: the next attempt waits, longer each time in a row.
ReadResult ReconnectingSource::begin_gap_or_continue(const std::string& why, Clock::time_point now) {
  last_error_ = why;
  next_attempt_ = now + wait_;
  wait_ = std::min(std::chrono::duration_cast<Clock::duration>(wait_ * backoff_.factor),
                   std::chrono::duration_cast<Clock::duration>(backoff_.max));
  if (!gaps_.empty() && !gaps_.back().end) return result(ReadStatus::kTimeout, why);  // same gap
  ++gap_count_;
  gaps_.push_back({now, std::nullopt, why});
  if (gaps_.size() > kKeptGaps) gaps_.pop_front();
  return result(ReadStatus::kDisconnected, why);
}

std::string ReconnectingSource::describe() const {
  if (source_) return source_->describe() + (identity_.empty() ? "" : " [usb " + identity_ + "]");
  return name_ + " (disconnected" + (last_error_.empty() ? "" : ": " + last_error_) + ")";
}

std::uint64_t ReconnectingSource::lost_frames() const { return lost_before_ + (source_ ? source_->lost_frames() : 0); }

std::chrono::steady_clock::duration ReconnectingSource::disconnected_time() const {
  auto total = closed_gaps_time_;
  if (!gaps_.empty() && !gaps_.back().end) total += Clock::now() - gaps_.back().begin;
  return total;
}

}  // namespace cvo::drivers
