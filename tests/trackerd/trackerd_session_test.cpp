// cvo-trackerd's sessions across a camera that goes away and comes back. No device is attached to
// the machines that run the tests, so the camera is scripted at the boundary the driver tests use
// (tests/drivers/reconnecting_source_test.cpp): the real ReconnectingSource over an opener whose
// first source yields frames 0-24 of the sample and then reports the device unplugged, and whose
// second yields frames 25-49 and ends. The daemon runs in this process (Trackerd, its three threads,
// a file:// LCM log as output); this binary counts the tracking thread's allocations.
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "daemon/common/signals.hpp"
#include "daemon/trackerd/trackerd.hpp"
#include "drivers/reconnecting_source.hpp"
#include "tests/support/lcm_log.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon::trackerd {
namespace {

using namespace std::chrono_literals;

const std::string kSample = std::string(CVO_TEST_DATA_DIR) + "/fr1_rpy_50";
constexpr int kPerConnection = 25;

// Frames [first, first + count) of the sample, then `then` (the device unplugged, or the end).
class ScriptedCamera final : public drivers::FrameSource {
 public:
  ScriptedCamera(int first, int count, drivers::ReadStatus then) : count_(count), then_(then) {
    drivers::SourceOptions options;
    options.realtime = false;
    sample_ = drivers::open_source("tum:" + kSample, options);
    core::RgbdFrame skipped;
    for (int i = 0; i < first; ++i) sample_->read(skipped, 1s);
  }
  drivers::ReadResult read(core::RgbdFrame& frame, std::chrono::milliseconds timeout) override {
    if (served_ == count_) return {then_, core::BadKind::kContent, "scripted camera: unplugged"};
    const auto result = sample_->read(frame, timeout);
    served_ += result.status == drivers::ReadStatus::kFrame;
    return result;
  }
  [[nodiscard]] std::string describe() const override { return "scripted camera"; }

 private:
  std::unique_ptr<drivers::FrameSource> sample_;
  int count_, served_ = 0;
  drivers::ReadStatus then_;
};

std::string hex(std::int64_t session) {
  char text[19];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(session));
  return text;
}

TEST(TrackerdSessions, CameraThatComesBackIsANewSessionFromFrameZero) {
  cvo::test::TempDir dir;
  const auto out = dir.path() / "out.lcmlog";
  config::Config config;
  config.trackerd.source = "scripted:camera";
  config.trackerd.lcm_url = "file://" + out.string() + "?mode=w";
  config.trackerd.realtime_priority = 0;
  config.trackerd.lock_memory = false;
  config.trackerd.exit_on_eof = true;
  config.trackerd.deterministic = true;
  config.trackerd.warmup_frames = 10;  // the re-initialisation comes after the warm-up: it must not allocate
  int opened = 0;
  const auto camera = [&opened]() -> std::unique_ptr<drivers::FrameSource> {
    const bool first = opened++ == 0;
    return std::make_unique<ScriptedCamera>(
        first ? 0 : kPerConnection, kPerConnection,
        first ? drivers::ReadStatus::kDisconnected : drivers::ReadStatus::kEndOfStream);
  };
  block_stop_signals();
  ::testing::internal::CaptureStderr();
  int code = -1;
  {
    Trackerd trackerd(config, [&] {
      return std::make_unique<drivers::ReconnectingSource>("scripted camera", camera,
                                                           drivers::Backoff{10ms, 10ms, 2.0});
    });
    code = trackerd.run();
  }
  const std::string err = ::testing::internal::GetCapturedStderr();
  ASSERT_EQ(code, 0) << err;
  EXPECT_EQ(opened, 2) << err;

  const auto log = cvo::testing::read_published(out);
  ASSERT_EQ(log.poses.size(), 2u * kPerConnection) << err;
  const std::int64_t a = log.poses.front().session, b = log.poses.back().session;
  EXPECT_NE(a, 0);
  EXPECT_NE(b, 0);
  EXPECT_NE(a, b) << "the camera came back: a new session";
  // Frame indices count from 0 in each session; the new one starts from scratch: first frame,
  // a keyframe at the odometry origin.
  for (std::size_t i = 0; i < log.poses.size(); ++i) {
    const auto& p = log.poses[i];
    const bool second = i >= kPerConnection;
    EXPECT_EQ(p.session, second ? b : a) << i;
    EXPECT_EQ(p.frame_index, static_cast<std::int64_t>(second ? i - kPerConnection : i)) << i;
  }
  const auto& restart = log.poses[kPerConnection];
  EXPECT_EQ(restart.status, +cvo_lcm::pose_t::STATUS_FIRST_FRAME);
  EXPECT_TRUE(restart.is_keyframe);
  EXPECT_EQ(restart.keyframe_id, 0);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(restart.odom_pose.position[k], 0.0);
  EXPECT_EQ(restart.odom_pose.orientation[0], 1.0);

  // Per session: keyframe ids from 0, each keyframe's local graph published, the open one too, so
  // the back end has every frame of both sessions.
  for (const std::int64_t session : {a, b}) {
    std::vector<const cvo_lcm::keyframe_t*> keyframes;
    std::vector<const cvo_lcm::local_graph_t*> graphs;
    for (const auto& k : log.keyframes)
      if (k.session == session) keyframes.push_back(&k);
    for (const auto& g : log.local_graphs)
      if (g.session == session) graphs.push_back(&g);
    ASSERT_FALSE(keyframes.empty());
    ASSERT_EQ(graphs.size(), keyframes.size()) << hex(session);
    for (std::size_t i = 0; i < keyframes.size(); ++i) {
      EXPECT_EQ(keyframes[i]->id, static_cast<std::int64_t>(i));
      EXPECT_EQ(graphs[i]->keyframe_id, keyframes[i]->id);
    }
    EXPECT_EQ(keyframes.front()->frame_index, 0);
    EXPECT_EQ(graphs.back()->nodes.back().frame_index, kPerConnection - 1) << hex(session) << "'s last frame";
  }
  for (const auto& s : log.statuses) EXPECT_TRUE(s.session == a || s.session == b) << hex(s.session);

  ASSERT_FALSE(log.statuses.empty());
  const auto& last = log.statuses.back();
  EXPECT_EQ(last.session, b);
  EXPECT_EQ(last.source_gaps, 1);
  EXPECT_EQ(last.allocations_after_warmup, 0) << "the new session is started without allocating";
  EXPECT_NE(err.find("session " + hex(a)), std::string::npos) << err;
  EXPECT_NE(err.find("camera re-initialised: new session " + hex(b)), std::string::npos) << err;
}

}  // namespace
}  // namespace cvo::daemon::trackerd
