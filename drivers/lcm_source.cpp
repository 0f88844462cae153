#include "drivers/lcm_source.hpp"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <chrono>
#include <climits>
#include <optional>
#include <string>

#include "drivers/frame_gaps.hpp"
#include "drivers/read_result.hpp"
#include "libcvo/auth/authenticator.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"

namespace cvo::drivers {
namespace {

using Clock = std::chrono::steady_clock;

// Messages LCM may hold for us between two reads: about two seconds of a 30 Hz camera, so that a
// stall of the consumer (a keyframe, a loop closure) delays frames instead of dropping them.
// LCM's default is 30.
constexpr int kQueueCapacity = 64;

class LcmSource final : public FrameSource {
 public:
  LcmSource(std::string url, const SourceOptions& options)
      : url_(std::move(url)),
        channel_(options.lcm_channel),
        is_log_(url_.starts_with("file://")),
        lcm_(url_),
        verifier_(options.bus_keys, options.bus_max_age_us, !is_log_) {
    if (!lcm_.good())
      throw SourceError("lcm:" + url_,
                        "LCM cannot open this provider (a bad URL, or a log file that is missing or empty)");
    ::lcm::Subscription* subscription = lcm_.subscribe(channel_, &LcmSource::on_message, this);
    if (subscription == nullptr) throw SourceError("lcm:" + url_, "cannot subscribe to channel " + channel_);
    subscription->setQueueCapacity(kQueueCapacity);
  }
  // on_message is registered with `this`.
  LcmSource(const LcmSource&) = delete;
  LcmSource& operator=(const LcmSource&) = delete;

  ReadResult read(core::RgbdFrame& frame, std::chrono::milliseconds timeout) override {
    target_ = &frame;
    result_.reset();
    const ReadResult outcome = wait_for_message(Clock::now() + timeout);
    target_ = nullptr;
    return outcome;
  }

  [[nodiscard]] std::string describe() const override {
    return "lcm:" + (url_.empty() ? std::string("(LCM default)") : url_) + " channel " + channel_;
  }

  [[nodiscard]] std::uint64_t lost_frames() const override { return gaps_.lost() + overflow_; }

 private:
  ReadResult wait_for_message(Clock::time_point deadline) {
    // One handleTimeout() dispatches at most one event; events of other channels dispatch nothing.
    for (;;) {
      const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()).count();
      const int status = lcm_.handleTimeout(static_cast<int>(std::clamp<long long>(left, 0, INT_MAX)));
      if (result_) return *result_;
      if (status < 0) {
        // LCM's file provider fails every handle() after its last event; a live one only on error.
        if (is_log_) return result(ReadStatus::kEndOfStream);
        return result(ReadStatus::kDisconnected, "lcm:" + url_ + ": LCM stopped receiving");
      }
      if (status == 0) return result(ReadStatus::kTimeout);
    }
  }

  void on_message(const ::lcm::ReceiveBuffer* buffer, const std::string& channel) {
    if (result_ || target_ == nullptr) {  // cannot happen (one event per handle), but never silently
      ++overflow_;
      return;
    }
    if (buffer->data_size > static_cast<std::uint32_t>(INT_MAX)) {
      gaps_.unreadable();
      result_ =
          bad_input(core::BadKind::kBody, "CVO_RGBD: a message of " + std::to_string(buffer->data_size) + " bytes");
      return;
    }
    if (const auto v = verifier_.verify(channel, buffer->data, buffer->data_size); v.verdict != auth::Verdict::kOk) {
      gaps_.unreadable();  // never decoded
      result_ = bad_input(v.verdict == auth::Verdict::kReplay ? core::BadKind::kReplay : core::BadKind::kAuth,
                          channel + ": " + v.why);
      return;
    }
    std::string error;
    lcm::DecodeFailure failure = lcm::DecodeFailure::kBody;
    const auto message =
        lcm::decode<cvo_lcm::rgbd_frame_t>(buffer->data, static_cast<int>(buffer->data_size), &error, &failure);
    if (!message) {
      gaps_.unreadable();
      result_ = bad_input(failure, error);
      return;
    }
    if (message->frame_index >= 0) gaps_.arrived(message->frame_index);
    core::BadKind kind = core::BadKind::kContent;
    auto frame = lcm::from_message(*message, &error, &kind);
    if (!frame) {
      result_ = bad_input(kind, error);
      return;
    }
    *target_ = std::move(*frame);
    result_ = result(ReadStatus::kFrame);
  }

  const std::string url_;
  const std::string channel_;
  const bool is_log_;
  ::lcm::LCM lcm_;
  auth::Verifier verifier_;            // before any decoding (an open bus: accepts all)
  core::RgbdFrame* target_ = nullptr;  // the frame of the read() in progress
  std::optional<ReadResult> result_;   // what the handler made of the message it was given
  FrameGaps gaps_;
  std::uint64_t overflow_ = 0;
};

}  // namespace

std::unique_ptr<FrameSource> open_lcm(std::string_view url, const SourceOptions& options) {
  return std::make_unique<LcmSource>(std::string(url), options);
}

}  // namespace cvo::drivers
