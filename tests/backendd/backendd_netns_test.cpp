// cvo-backendd end to end over real LCM UDP multicast: a tracker recording's keyframes and local
// graphs are played into the daemon, which is killed (SIGKILL) half-way and restarted; the final
// CVO_MAP still holds every keyframe sent, and the restart says it recovered them from its store.
//
// Runs only inside tests/support/in-private-netns (CVO_PRIVATE_NETNS=1): lo alone, no packet can
// leave the host.
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "tests/daemon/daemon_process.hpp"
#include "tests/daemon/lcm_log.hpp"
#include "tests/daemon/private_network.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::DaemonProcess;
using cvo::testing::which;

constexpr const char* kUrl = cvo::testing::kPrivateLcmUrl;
const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";

// The tracker's output on the clip, split into two logs of its keyframes and local graphs.
std::vector<std::int64_t> tracker_recording(const fs::path& dir, fs::path& first, fs::path& second) {
  const auto out = dir / "tracker.lcmlog";
  DaemonProcess trackerd(fs::path(CVO_TOOLS_DIR) / "cvo-trackerd",
                         {"--source", "tum:" + kClip.string(), "--exit-on-eof", "--deterministic", "--lcm-url",
                          "file://" + out.string() + "?mode=w", "--set", "trackerd.paced=false", "--set",
                          "trackerd.realtime_priority=0", "--set", "trackerd.lock_memory=false"},
                         dir / "tracker.txt");
  EXPECT_EQ(trackerd.wait_for(120s).value_or(-9), 0);
  std::vector<std::int64_t> keyframe_ids;
  ::lcm::LogFile in(out.string(), "r");
  std::vector<::lcm::LogEvent> events;
  std::vector<std::vector<std::uint8_t>> data;
  while (const ::lcm::LogEvent* e = in.readNextEvent()) {
    if (e->channel != "CVO_KEYFRAME" && e->channel != "CVO_LOCAL_GRAPH") continue;
    if (e->channel == "CVO_KEYFRAME") {
      const auto k = cvo::lcm::decode<cvo_lcm::keyframe_t>(e->data, e->datalen, nullptr);
      keyframe_ids.push_back(k ? k->id : -1);
    }
    events.push_back(*e);
    data.emplace_back(static_cast<const std::uint8_t*>(e->data), static_cast<const std::uint8_t*>(e->data) + e->datalen);
  }
  first = dir / "first.lcmlog";
  second = dir / "second.lcmlog";
  ::lcm::LogFile a(first.string(), "w"), b(second.string(), "w");
  std::int64_t t = 0;
  for (std::size_t i = 0; i < events.size(); ++i) {
    auto e = events[i];
    e.data = data[i].data();
    e.timestamp = t += 200000;  // 5 Hz: the back end keeps up, nothing queues in the socket
    (i < events.size() / 2 ? a : b).writeEvent(&e);
  }
  return keyframe_ids;
}

TEST(BackenddNetns, KilledAndRestartedMidReplayLosesNoKeyframe) {
  if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
  cvo::test::TempDir dir;
  fs::path first, second;
  const auto keyframe_ids = tracker_recording(dir.path(), first, second);
  ASSERT_GE(keyframe_ids.size(), 4u);

  const auto store = dir.path() / "state" / "keyframes.store";
  const auto maps = dir.path() / "maps.lcmlog";
  const std::vector<std::string> args{"--lcm-url", kUrl, "--store", store.string()};
  const auto backendd_exe = fs::path(CVO_TOOLS_DIR) / "cvo-backendd";
  DaemonProcess logger(which("lcm-logger"), {"--lcm-url=" + std::string(kUrl), "-c", "CVO_(MAP|STATUS)", "-f", maps.string()},
                       dir.path() / "logger.txt");
  const auto play = [&](const fs::path& log) {
    DaemonProcess player(which("lcm-logplayer"), {"--lcm-url=" + std::string(kUrl), log.string()}, dir.path() / "player.txt");
    EXPECT_TRUE(player.wait_for(60s));
  };
  {
    DaemonProcess backendd(backendd_exe, args, dir.path() / "backendd1.txt");
    std::this_thread::sleep_for(1000ms);
    play(first);
    std::this_thread::sleep_for(1000ms);
    ASSERT_TRUE(backendd.running()) << cvo::testing::slurp(dir.path() / "backendd1.txt");
    backendd.signal(SIGKILL);  // no chance to flush anything
    backendd.wait_for(5s);
  }
  DaemonProcess backendd(backendd_exe, args, dir.path() / "backendd2.txt");
  std::this_thread::sleep_for(1500ms);
  play(second);
  std::this_thread::sleep_for(2000ms);
  backendd.signal(SIGTERM);
  const auto code = backendd.wait_for(30s);
  const auto err = cvo::testing::slurp(dir.path() / "backendd2.txt");
  ASSERT_TRUE(code) << err;
  EXPECT_EQ(*code, 0) << err;
  EXPECT_EQ(err.find(" 0 records recovered"), std::string::npos) << "the restart found nothing in its store:\n" << err;
  std::this_thread::sleep_for(300ms);
  logger.signal(SIGINT);
  logger.wait_for(5s);

  const auto published = cvo::testing::read_published(maps);
  ASSERT_FALSE(published.maps.empty()) << err;
  const auto& last = published.maps.back();
  const std::set<std::int64_t> in_map(last.keyframe_ids.begin(), last.keyframe_ids.end());
  for (const auto id : keyframe_ids) EXPECT_TRUE(in_map.count(id)) << "keyframe " << id << " lost\n" << err;
  EXPECT_EQ(in_map.size(), keyframe_ids.size());
  ASSERT_FALSE(published.statuses.empty());
  EXPECT_EQ(published.statuses.back().process, "cvo-backendd");
  EXPECT_EQ(published.statuses.back().state, +cvo_lcm::status_t::STATE_STOPPING);
}

}  // namespace
}  // namespace cvo::daemon
