#include "drivers/reconnecting_source.hpp"

#include <algorithm>
#include <thread>

#include "drivers/read_result.hpp"

namespace cvo::drivers {

ReconnectingSource::ReconnectingSource(std::string spec, SourceOptions options, Backoff backoff)
    : ReconnectingSource(spec, [spec, options = std::move(options)] { return open_source(spec, options); }, backoff) {}

ReconnectingSource::ReconnectingSource(std::string name, Opener open, Backoff backoff)
    : name_(std::move(name)), open_(std::move(open)), backoff_(backoff), wait_(backoff.initial) {}

ReadResult ReconnectingSource::read(core::RgbdFrame& frame, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  if (!source_) {
    if (auto not_open = try_open(deadline)) return *not_open;
  }
  const auto left = std::max(std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()),
                             std::chrono::milliseconds(0));
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
  if (next_attempt_ > deadline) {  // not due within this read
    std::this_thread::sleep_until(deadline);
    return result(ReadStatus::kTimeout, last_error_);
  }
  std::this_thread::sleep_until(next_attempt_);
  ++attempts_;
  try {
    source_ = open_();
  } catch (const SourceError& e) {
    return begin_gap_or_continue(e.what(), Clock::now());
  }
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
  if (source_) return source_->describe();
  return name_ + " (disconnected" + (last_error_.empty() ? "" : ": " + last_error_) + ")";
}

std::uint64_t ReconnectingSource::lost_frames() const {
  return lost_before_ + (source_ ? source_->lost_frames() : 0);
}

std::chrono::steady_clock::duration ReconnectingSource::disconnected_time() const {
  auto total = closed_gaps_time_;
  if (!gaps_.empty() && !gaps_.back().end) total += Clock::now() - gaps_.back().begin;
  return total;
}

}  // namespace cvo::drivers
