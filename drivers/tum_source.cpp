#include "drivers/tum_source.hpp"

#include <chrono>
#include <stdexcept>
#include <thread>

#include "drivers/read_result.hpp"
#include "libcvo/io/tum_dataset.hpp"

namespace cvo::drivers {
namespace {

using Clock = std::chrono::steady_clock;

class TumSource final : public FrameSource {
 public:
  TumSource(io::TumSequence sequence, bool realtime) : sequence_(std::move(sequence)), realtime_(realtime) {}

  ReadResult read(core::RgbdFrame& frame, std::chrono::milliseconds timeout) override {
    const std::size_t i = sequence_.position();
    if (i >= sequence_.size()) return result(ReadStatus::kEndOfStream);
    if (realtime_) {
      const auto due = due_time(sequence_.files()[i].timestamp);
      if (const auto deadline = Clock::now() + timeout; due > deadline) {  // wait what we may, no more
        std::this_thread::sleep_until(deadline);
        return result(ReadStatus::kTimeout);
      }
      std::this_thread::sleep_until(due);
    }
    try {
      frame = *sequence_.next();         // position < size, so there is a next frame
    } catch (const io::FrameError& e) {  // next() has moved past it: the following read goes on
      return bad_input(core::BadKind::kContent, e.what());
    }
    return result(ReadStatus::kFrame);
  }

  [[nodiscard]] std::string describe() const override {
    return "tum:" + sequence_.directory().string() + " (" + std::to_string(sequence_.size()) + " frames, " +
           (realtime_ ? "realtime" : "as fast as possible") + ")";
  }

 private:
  // The first frame is due when it is first asked for; every later one at its offset from it.
  Clock::time_point due_time(double timestamp) {
    if (!anchor_) anchor_ = Anchor{Clock::now(), timestamp};
    const std::chrono::duration<double> offset(timestamp - anchor_->timestamp);
    return anchor_->time + std::chrono::duration_cast<Clock::duration>(offset);
  }

  struct Anchor {
    Clock::time_point time;
    double timestamp = 0;
  };

  io::TumSequence sequence_;
  const bool realtime_;
  std::optional<Anchor> anchor_;
};

}  // namespace

std::unique_ptr<FrameSource> open_tum(const std::filesystem::path& dir, const SourceOptions& options) {
  io::TumOptions tum_options;
  tum_options.intrinsics = options.intrinsics;
  try {
    return std::make_unique<TumSource>(io::TumSequence::open(dir, tum_options), options.realtime);
  } catch (const io::InputError& e) {
    throw SourceError(e);
  } catch (const std::invalid_argument& e) {  // intrinsics that TumSequence refuses
    throw SourceError(dir, e.what());
  }
}

}  // namespace cvo::drivers
