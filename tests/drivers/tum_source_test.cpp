// tum: the embedded sample as a frame source: every frame in order, paced at the recorded rate
// when asked, a damaged frame reported and skipped, reads that never wait past their timeout.
#include <chrono>
#include <fstream>
#include <vector>

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "drivers/frame_source.hpp"
#include "drivers/open_source.hpp"
#include "drivers/tum_copy.hpp"
#include "support/temp_dir.hpp"

namespace cvo::drivers {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;
using test::kSample;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

SourceOptions as_fast_as_possible() {
  SourceOptions o;
  o.realtime = false;
  return o;
}

TEST(TumSource, EveryFrameInOrderThenEndOfStream) {
  const auto expected = io::TumSequence::open(kSample);
  auto source = open_source("tum:" + kSample.string(), as_fast_as_possible());
  EXPECT_NE(source->describe().find("50 frames"), std::string::npos) << source->describe();

  core::RgbdFrame frame;
  std::vector<double> stamps;
  for (ReadResult r; (r = source->read(frame, milliseconds(1000))).status != ReadStatus::kEndOfStream;) {
    ASSERT_EQ(r.status, ReadStatus::kFrame) << r.message;
    EXPECT_EQ(frame.index, stamps.size());
    EXPECT_EQ(frame.bgr.type(), CV_8UC3);
    EXPECT_EQ(frame.depth.type(), CV_16UC1);
    EXPECT_EQ(frame.intrinsics.fx, expected.intrinsics().fx);
    stamps.push_back(frame.timestamp);
  }
  ASSERT_EQ(stamps.size(), expected.size());
  for (std::size_t i = 1; i < stamps.size(); ++i) EXPECT_GT(stamps[i], stamps[i - 1]) << i;
  EXPECT_EQ(source->read(frame, milliseconds(10)).status, ReadStatus::kEndOfStream) << "and stays at the end";
}

// Wall time to read the first n frames.
double time_to_read(FrameSource& source, int n) {
  core::RgbdFrame frame;
  Clock::time_point first{};
  for (int i = 0; i < n; ++i) {
    const auto r = source.read(frame, milliseconds(2000));
    EXPECT_EQ(r.status, ReadStatus::kFrame) << r.message;
    if (i == 0) first = Clock::now();
  }
  return seconds_since(first);
}

TEST(TumSource, RealtimeTakesTheRecordedTime) {
  const int n = 10;
  const auto files = io::TumSequence::open(kSample).files();
  const double recorded = files[n - 1].timestamp - files[0].timestamp;  // about 0.3 s
  SourceOptions realtime;
  realtime.realtime = true;
  auto paced = open_source("tum:" + kSample.string(), realtime);
  EXPECT_NE(paced->describe().find("realtime"), std::string::npos) << paced->describe();
  EXPECT_GE(time_to_read(*paced, n), 0.8 * recorded);
}

TEST(TumSource, AsFastAsPossibleIsNotPaced) {
  // Frames half a second apart, so that decoding time on a loaded machine cannot blur the order.
  test::TempDir dir;
  const auto folder = dir.path() / "fr1_slow";
  test::write_tum_copy(folder, 3, std::vector<double>{10.0, 10.5, 11.0});
  SourceOptions realtime;
  realtime.realtime = true;
  auto paced = open_source("tum:" + folder.string(), realtime);
  auto fast = open_source("tum:" + folder.string(), as_fast_as_possible());
  const double paced_s = time_to_read(*paced, 3);
  const double fast_s = time_to_read(*fast, 3);
  EXPECT_GE(paced_s, 0.8);
  EXPECT_LT(fast_s, 0.5);
  EXPECT_LT(fast_s, paced_s);
}

TEST(TumSource, RealtimeReadsNeverWaitPastTheirTimeout) {
  test::TempDir dir;
  const auto folder = dir.path() / "fr1_sparse";
  test::write_tum_copy(folder, 2, std::vector<double>{100.0, 101.5});  // the second frame 1.5 s after the first
  auto source = open_source("tum:" + folder.string());                 // realtime by default

  core::RgbdFrame frame;
  ASSERT_EQ(source->read(frame, milliseconds(1000)).status, ReadStatus::kFrame);
  const auto start = Clock::now();
  const auto early = source->read(frame, milliseconds(200));
  const double waited = seconds_since(start);
  EXPECT_EQ(early.status, ReadStatus::kTimeout);
  EXPECT_GE(waited, 0.19);
  EXPECT_LT(waited, 1.0) << "waited for the frame instead of returning at the timeout";

  const auto due = source->read(frame, milliseconds(5000));
  EXPECT_EQ(due.status, ReadStatus::kFrame);
  EXPECT_GE(seconds_since(start), 0.8 * 1.5);
  EXPECT_EQ(frame.timestamp, 101.5);
}

TEST(TumSource, CorruptImageIsBadInputAndTheNextReadGoesOn) {
  test::TempDir dir;
  const auto folder = dir.path() / "fr1_damaged";
  test::write_tum_copy(folder, 5);
  const auto damaged = io::TumSequence::open(folder).files()[2].depth;
  std::ofstream(damaged, std::ios::binary | std::ios::trunc) << "\x89PNG\r\n\x1a\n not really";

  auto source = open_source("tum:" + folder.string(), as_fast_as_possible());
  core::RgbdFrame frame;
  std::vector<std::uint64_t> indices;
  for (int k = 0; k < 5; ++k) {
    const auto r = source->read(frame, milliseconds(1000));
    if (k == 2) {
      EXPECT_EQ(r.status, ReadStatus::kBadInput);
      EXPECT_EQ(r.bad_input, core::BadKind::kContent);
      EXPECT_NE(r.message.find(damaged.filename().string()), std::string::npos) << r.message;
      continue;
    }
    ASSERT_EQ(r.status, ReadStatus::kFrame) << k << ": " << r.message;
    indices.push_back(frame.index);
  }
  EXPECT_EQ(indices, (std::vector<std::uint64_t>{0, 1, 3, 4}));
  EXPECT_EQ(source->read(frame, milliseconds(10)).status, ReadStatus::kEndOfStream);
}

TEST(TumSource, GivenIntrinsicsWin) {
  SourceOptions o = as_fast_as_possible();
  o.intrinsics = core::Intrinsics{600, 601, 320, 240, 640, 480, 5000};
  auto source = open_source("tum:" + kSample.string(), o);
  core::RgbdFrame frame;
  ASSERT_EQ(source->read(frame, milliseconds(1000)).status, ReadStatus::kFrame);
  EXPECT_EQ(frame.intrinsics.fx, 600);
  EXPECT_EQ(frame.intrinsics.fy, 601);
}

}  // namespace
}  // namespace cvo::drivers
