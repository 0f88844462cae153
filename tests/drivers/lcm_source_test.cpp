// lcm: CVO_RGBD messages replayed from a log by LCM's file provider: every refused message is
// reported with the right kind and in order, frames come through bit-exact, the end of the log is
// the end of the stream, and lost frames are counted. With the deployment's keys, only frames
// signed with one of them come through; the rest are refused as kAuth before decoding.
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "cvo_lcm/pose_t.hpp"
#include "drivers/frame_source.hpp"
#include "drivers/open_source.hpp"
#include "drivers/tum_copy.hpp"
#include "libcvo/auth/authenticator.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"
#include "support/run_tool.hpp"
#include "support/temp_dir.hpp"

namespace cvo::drivers {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using Bytes = std::vector<std::uint8_t>;
using std::chrono::milliseconds;

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0;
}

// A small frame with distinct pixels, numbered `index`.
core::RgbdFrame small_frame(std::uint64_t index) {
  core::RgbdFrame f;
  f.index = index;
  f.timestamp = 1000.0 + 0.1 * static_cast<double>(index);
  f.depth_timestamp = f.timestamp + 0.001;
  f.intrinsics = {50, 50, 4, 3, 8, 6, 5000};
  f.bgr = cv::Mat(6, 8, CV_8UC3);
  f.depth = cv::Mat(6, 8, CV_16UC1);
  cv::randu(f.bgr, 0, 256);
  cv::randu(f.depth, 0, 65535);
  return f;
}

cvo_lcm::rgbd_frame_t message_of(const core::RgbdFrame& frame) {
  lcm::RgbdEncoding raw;
  raw.colour = lcm::ColourEncoding::kRawBgr8;
  raw.depth = lcm::DepthEncoding::kRawU16Le;
  std::string error;
  const auto m = lcm::to_message(frame, raw, &error);
  EXPECT_TRUE(m) << error;
  return m.value_or(cvo_lcm::rgbd_frame_t{});
}

struct Event {
  std::string channel;
  Bytes data;
};

void write_log(const fs::path& file, const std::vector<Event>& events, std::int64_t spacing_us = 1000) {
  ::lcm::LogFile log(file.string(), "w");
  ASSERT_TRUE(log.good());
  std::int64_t t = 1'000'000;
  for (const auto& e : events) {
    ::lcm::LogEvent event{};
    event.timestamp = t;
    t += spacing_us;
    event.channel = e.channel;
    event.datalen = static_cast<std::int32_t>(e.data.size());
    event.data = const_cast<std::uint8_t*>(e.data.data());
    ASSERT_EQ(log.writeEvent(&event), 0);
  }
}

std::string replay_url(const fs::path& log) { return "lcm:file://" + log.string() + "?speed=0"; }

TEST(LcmSource, EachRefusedMessageIsReportedWithItsKindInOrder) {
  test::TempDir dir;
  const auto log = dir.path() / "mixed.lcm";
  const auto first = small_frame(0), last = small_frame(1);

  const Bytes good = lcm::encode(message_of(first));
  Bytes truncated = good;
  truncated.resize(good.size() - 10);
  Bytes oversized = good;
  oversized.insert(oversized.end(), {1, 2, 3});
  auto other_version = message_of(first);
  other_version.version = cvo_lcm::rgbd_frame_t::SCHEMA_VERSION + 1;
  auto short_raw = message_of(first);  // consistent counts, but 3 bytes short of 8x6 BGR
  short_raw.colour.resize(short_raw.colour.size() - 3);
  short_raw.colour_size = static_cast<std::int32_t>(short_raw.colour.size());
  auto mislabelled = message_of(first);  // raw pixels said to be a PNG: no decoder may see them
  mislabelled.colour_encoding = cvo_lcm::rgbd_frame_t::COLOUR_PNG;
  cvo_lcm::pose_t pose{};
  pose.version = cvo_lcm::pose_t::SCHEMA_VERSION;

  write_log(log, {{"CVO_RGBD", good},
                  {"CVO_RGBD", {1, 2, 3, 4}},
                  {"CVO_RGBD", lcm::encode(pose)},
                  {"CVO_RGBD", truncated},
                  {"CVO_RGBD", oversized},
                  {"CVO_RGBD", lcm::encode(other_version)},
                  {"CVO_RGBD", lcm::encode(short_raw)},
                  {"CVO_RGBD", lcm::encode(mislabelled)},
                  {"CVO_POSE", lcm::encode(pose)},  // another channel: not ours, skipped
                  {"CVO_RGBD", lcm::encode(message_of(last))}});

  auto source = open_source(replay_url(log));
  core::RgbdFrame frame;
  auto r = source->read(frame, milliseconds(2000));
  ASSERT_EQ(r.status, ReadStatus::kFrame) << r.message;
  EXPECT_TRUE(identical(frame.bgr, first.bgr));
  EXPECT_TRUE(identical(frame.depth, first.depth));
  EXPECT_EQ(frame.intrinsics.fx, 50);

  const std::string next_version = std::to_string(cvo_lcm::rgbd_frame_t::SCHEMA_VERSION + 1);
  const std::vector<std::pair<core::BadKind, std::string>> refused{
      {core::BadKind::kTooShort, "shorter than"},
      {core::BadKind::kFingerprint, "fingerprint"},
      {core::BadKind::kBody, "truncated"},
      {core::BadKind::kBody, "trailing bytes"},
      {core::BadKind::kVersion, "schema version " + next_version},
      {core::BadKind::kContent, "raw colour needs"},
      {core::BadKind::kImageFormat, "not a PNG"}};
  for (const auto& [kind, words] : refused) {
    r = source->read(frame, milliseconds(2000));
    EXPECT_EQ(r.status, ReadStatus::kBadInput) << words;
    EXPECT_EQ(r.bad_input, kind) << words << ": " << to_string(r.bad_input) << ", " << r.message;
    EXPECT_NE(r.message.find(words), std::string::npos) << r.message;
  }
  r = source->read(frame, milliseconds(2000));
  ASSERT_EQ(r.status, ReadStatus::kFrame) << r.message;
  EXPECT_EQ(frame.index, 1u);
  EXPECT_TRUE(identical(frame.bgr, last.bgr));

  EXPECT_EQ(source->read(frame, milliseconds(2000)).status, ReadStatus::kEndOfStream);
  EXPECT_EQ(source->read(frame, milliseconds(2000)).status, ReadStatus::kEndOfStream) << "and stays at the end";
  EXPECT_EQ(source->lost_frames(), 0u);
}

TEST(LcmSource, GapsInTheSendersFrameNumbersAreCountedLost) {
  test::TempDir dir;
  const auto log = dir.path() / "gaps.lcm";
  // Frames 0, (one unreadable), 2, 5: frame 1 arrived but was refused; 3 and 4 never arrived.
  write_log(log, {{"CVO_RGBD", lcm::encode(message_of(small_frame(0)))},
                  {"CVO_RGBD", {9, 9}},
                  {"CVO_RGBD", lcm::encode(message_of(small_frame(2)))},
                  {"CVO_RGBD", lcm::encode(message_of(small_frame(5)))}});
  auto source = open_source(replay_url(log));
  core::RgbdFrame frame;
  int frames = 0, bad = 0;
  for (ReadResult r; (r = source->read(frame, milliseconds(2000))).status != ReadStatus::kEndOfStream;) {
    ASSERT_NE(r.status, ReadStatus::kTimeout);
    frames += r.status == ReadStatus::kFrame;
    bad += r.status == ReadStatus::kBadInput;
  }
  EXPECT_EQ(frames, 3);
  EXPECT_EQ(bad, 1);
  EXPECT_EQ(source->lost_frames(), 2u);
}

TEST(LcmSource, ChannelOptionAndTimeout) {
  test::TempDir dir;
  const auto log = dir.path() / "slow.lcm";
  // Played at the recorded rate (speed=1): the second frame comes 5 s after the first.
  write_log(
      log,
      {{"CAM_FRONT", lcm::encode(message_of(small_frame(0)))}, {"CAM_FRONT", lcm::encode(message_of(small_frame(1)))}},
      5'000'000);
  SourceOptions options;
  options.lcm_channel = "CAM_FRONT";
  auto source = open_source("lcm:file://" + log.string() + "?speed=1", options);
  EXPECT_NE(source->describe().find("CAM_FRONT"), std::string::npos) << source->describe();
  core::RgbdFrame frame;
  ASSERT_EQ(source->read(frame, milliseconds(2000)).status, ReadStatus::kFrame);
  const auto start = Clock::now();
  EXPECT_EQ(source->read(frame, milliseconds(100)).status, ReadStatus::kTimeout);
  const double waited = std::chrono::duration<double>(Clock::now() - start).count();
  EXPECT_GE(waited, 0.09);
  EXPECT_LT(waited, 1.0);
}

std::shared_ptr<const auth::KeyRing> new_keys() {
  std::vector<auth::Key> keys;
  keys.push_back(auth::Key::generate());
  return std::make_shared<const auth::KeyRing>(std::move(keys));
}

Bytes signed_frame(std::uint64_t index, const std::shared_ptr<const auth::KeyRing>& keys) {
  auto bytes = lcm::encode(message_of(small_frame(index)));
  auth::Signer(keys, 42).sign("CVO_RGBD", bytes);
  return bytes;
}

TEST(LcmSource, WithTheDeploymentsKeysOnlyFramesSignedWithThemComeThrough) {
  test::TempDir dir;
  const auto ours = new_keys();
  auto changed = signed_frame(3, ours);
  changed[40] ^= 1;
  const auto log = dir.path() / "signed.lcm";
  write_log(log, {{"CVO_RGBD", signed_frame(0, ours)},
                  {"CVO_RGBD", lcm::encode(message_of(small_frame(1)))},  // unsigned: an open-bus driver
                  {"CVO_RGBD", signed_frame(2, new_keys())},              // another deployment's
                  {"CVO_RGBD", changed},
                  {"CVO_RGBD", signed_frame(4, ours)}});
  SourceOptions options;
  options.bus_keys = ours;
  auto source = open_source(replay_url(log), options);
  core::RgbdFrame frame;
  std::vector<std::uint64_t> frames;
  int refused = 0;
  for (ReadResult r; (r = source->read(frame, milliseconds(2000))).status != ReadStatus::kEndOfStream;) {
    if (r.status == ReadStatus::kFrame) frames.push_back(frame.index);
    if (r.status == ReadStatus::kBadInput) {
      EXPECT_EQ(r.bad_input, core::BadKind::kAuth) << r.message;
      ++refused;
    }
  }
  EXPECT_EQ(frames, (std::vector<std::uint64_t>{0, 4}));
  EXPECT_EQ(refused, 3);
  // Without keys (an open bus) every frame decodes.
  auto open = open_source(replay_url(log));
  int decoded = 0;
  for (ReadResult r; (r = open->read(frame, milliseconds(2000))).status != ReadStatus::kEndOfStream;)
    decoded += r.status == ReadStatus::kFrame ? 1 : 0;
  EXPECT_EQ(decoded, 5);
}

TEST(LcmSource, MissingLogOrBadUrlIsSourceError) {
  for (const std::string spec : {"lcm:file:///no/such/log.lcm", "lcm:nosuchprovider://x"}) {
    try {
      open_source(spec);
      ADD_FAILURE() << spec << " opened";
    } catch (const SourceError& e) {
      EXPECT_NE(std::string(e.what()).find("LCM"), std::string::npos) << e.what();
    }
  }
}

TEST(LcmSource, Tum2LcmRecordingReplaysAsTheFolderFrames) {
  test::TempDir dir;
  const auto log = dir.path() / "fr1.lcmlog";
  const auto run = testing::run_tool(
      "tum2lcm", testing::quoted(test::kSample) + " " + testing::quoted(log) + " --max-frames 8", dir.path());
  ASSERT_EQ(run.exit_code, 0) << run.err;

  const auto tum = io::TumSequence::open(test::kSample);
  auto source = open_source(replay_url(log));
  core::RgbdFrame frame;
  std::size_t n = 0;
  for (ReadResult r; (r = source->read(frame, milliseconds(2000))).status != ReadStatus::kEndOfStream; ++n) {
    ASSERT_EQ(r.status, ReadStatus::kFrame) << r.message;
    const auto expected = tum.read(n);
    SCOPED_TRACE("frame " + std::to_string(n));
    EXPECT_EQ(frame.index, n);
    EXPECT_EQ(frame.timestamp, expected.timestamp);
    EXPECT_EQ(frame.depth_timestamp, expected.depth_timestamp);
    EXPECT_EQ(frame.intrinsics.fx, expected.intrinsics.fx);
    EXPECT_EQ(frame.intrinsics.depth_scale, expected.intrinsics.depth_scale);
    EXPECT_TRUE(identical(frame.bgr, expected.bgr));
    EXPECT_TRUE(identical(frame.depth, expected.depth));
  }
  EXPECT_EQ(n, 8u);
}

}  // namespace
}  // namespace cvo::drivers
