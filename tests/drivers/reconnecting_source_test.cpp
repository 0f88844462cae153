// ReconnectingSource: a source that is not there yet, or goes away, is opened again with
// exponential back-off; reads never wait past their timeout; gaps are recorded.
#include <chrono>
#include <vector>

#include <gtest/gtest.h>

#include "drivers/reconnecting_source.hpp"
#include "drivers/tum_copy.hpp"
#include "support/temp_dir.hpp"

namespace cvo::drivers {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

TEST(ReconnectingSource, TumFolderThatAppearsLaterIsPickedUp) {
  test::TempDir dir;
  const auto folder = dir.path() / "fr1_later";
  SourceOptions options;
  options.realtime = false;
  ReconnectingSource source("tum:" + folder.string(), options, Backoff{milliseconds(20), milliseconds(50), 2.0});

  core::RgbdFrame frame;
  const auto first = source.read(frame, milliseconds(100));
  ASSERT_EQ(first.status, ReadStatus::kDisconnected);
  EXPECT_NE(first.message.find("fr1_later"), std::string::npos) << first.message;
  EXPECT_FALSE(source.connected());

  test::write_tum_copy(folder, 3);
  ReadResult r;
  const auto start = Clock::now();
  while ((r = source.read(frame, milliseconds(100))).status == ReadStatus::kTimeout && seconds_since(start) < 5) {
  }
  ASSERT_EQ(r.status, ReadStatus::kFrame) << r.message;
  EXPECT_EQ(frame.index, 0u);
  EXPECT_TRUE(source.connected());
  EXPECT_NE(source.describe().find("3 frames"), std::string::npos) << source.describe();
  for (std::uint64_t i = 1; i < 3; ++i) {
    ASSERT_EQ(source.read(frame, milliseconds(1000)).status, ReadStatus::kFrame);
    EXPECT_EQ(frame.index, i);
  }
  EXPECT_EQ(source.read(frame, milliseconds(100)).status, ReadStatus::kEndOfStream) << "passed through, no reopen";

  EXPECT_GE(source.open_attempts(), 2u);
  EXPECT_EQ(source.reconnects(), 0u) << "the first open is not a reconnect";
  ASSERT_EQ(source.gap_count(), 1u);
  ASSERT_EQ(source.gaps().size(), 1u);
  ASSERT_TRUE(source.gaps()[0].end.has_value());
  EXPECT_GT(*source.gaps()[0].end, source.gaps()[0].begin);
  EXPECT_NE(source.gaps()[0].reason.find("fr1_later"), std::string::npos);
  EXPECT_GT(source.disconnected_time(), Clock::duration::zero());
}

// Yields `frames` frames, then reports the device gone.
class FlakySource final : public FrameSource {
 public:
  explicit FlakySource(int frames) : frames_(frames) {}
  ReadResult read(core::RgbdFrame& frame, milliseconds) override {
    if (read_ == frames_) return {ReadStatus::kDisconnected, core::BadKind::kContent, "flaky: unplugged"};
    frame.index = static_cast<std::uint64_t>(read_++);
    return {ReadStatus::kFrame, core::BadKind::kContent, {}};
  }
  [[nodiscard]] std::string describe() const override { return "flaky"; }
  [[nodiscard]] std::uint64_t lost_frames() const override { return 2; }

 private:
  int frames_, read_ = 0;
};

TEST(ReconnectingSource, LostSourceIsReopenedWithGrowingWaits) {
  std::vector<Clock::time_point> attempts;
  int opens = 0;
  const Backoff backoff{milliseconds(20), milliseconds(50), 2.0};
  ReconnectingSource source(
      "flaky",
      [&]() -> std::unique_ptr<FrameSource> {
        attempts.push_back(Clock::now());
        ++opens;
        // Open, then four failed attempts (the device is away), then open again.
        if (opens == 1 || opens == 6) return std::make_unique<FlakySource>(2);
        throw SourceError("flaky", "no device");
      },
      backoff);

  core::RgbdFrame frame;
  EXPECT_EQ(source.read(frame, milliseconds(100)).status, ReadStatus::kFrame);
  EXPECT_EQ(source.read(frame, milliseconds(100)).status, ReadStatus::kFrame);
  const auto lost = source.read(frame, milliseconds(100));
  EXPECT_EQ(lost.status, ReadStatus::kDisconnected);
  EXPECT_EQ(lost.message, "flaky: unplugged");
  const auto gone = Clock::now();

  std::vector<ReadStatus> statuses;
  ReadResult r;
  while ((r = source.read(frame, milliseconds(100))).status != ReadStatus::kFrame && seconds_since(gone) < 5)
    statuses.push_back(r.status);
  ASSERT_EQ(r.status, ReadStatus::kFrame);
  EXPECT_EQ(frame.index, 0u) << "a fresh source";
  for (const auto s : statuses) EXPECT_EQ(s, ReadStatus::kTimeout) << "one gap, reported once";
  EXPECT_EQ(opens, 6);

  // Waits before attempts 2..6: 20 ms after the loss, then 40, 50 (the cap), 50, 50 after each failure.
  const std::vector<milliseconds> waits{milliseconds(20), milliseconds(40), milliseconds(50), milliseconds(50),
                                        milliseconds(50)};
  auto previous = gone;
  for (std::size_t k = 0; k < waits.size(); ++k) {
    EXPECT_GE(attempts[k + 1] - previous, waits[k] - milliseconds(1)) << "attempt " << k + 2;
    previous = attempts[k + 1];
  }
  EXPECT_EQ(source.reconnects(), 1u);
  EXPECT_EQ(source.gap_count(), 1u);
  EXPECT_EQ(source.lost_frames(), 4u) << "both sources' losses";
  EXPECT_GE(source.disconnected_time(), milliseconds(200));
}

TEST(ReconnectingSource, BackOffNeverHoldsAReadPastItsTimeout) {
  int opens = 0;
  ReconnectingSource source(
      "never",
      [&]() -> std::unique_ptr<FrameSource> {
        ++opens;
        throw SourceError("never", "no device");
      },
      Backoff{milliseconds(400), milliseconds(400), 2.0});
  core::RgbdFrame frame;
  EXPECT_EQ(source.read(frame, milliseconds(50)).status, ReadStatus::kDisconnected);
  const auto start = Clock::now();
  const auto r = source.read(frame, milliseconds(50));
  const double waited = seconds_since(start);
  EXPECT_EQ(r.status, ReadStatus::kTimeout);
  EXPECT_EQ(r.message, "never: no device") << "why it is still away";
  EXPECT_GE(waited, 0.045);
  EXPECT_LT(waited, 0.3) << "waited for the back-off instead of returning at the timeout";
  EXPECT_EQ(opens, 1) << "the next attempt was not due yet";
}

}  // namespace
}  // namespace cvo::drivers
