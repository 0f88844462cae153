// Localization through the real daemons: a map is made by cvo-backendd from a recording of the
// first half of the embedded clip (a file:// log), or offline by cvo-run --mode slam --store; then cvo-backendd --set
// backendd.mode=localization serves it read only while a live cvo-trackerd (real LCM UDP multicast) runs the second
// half, a frame without depth (the camera covered: the odometry fails), and the whole clip again. CVO_POSE must say
// LOCALIZING, then LOCALIZED in the first session, LOST where the odometry failed, and LOCALIZED again in the session
// that follows; the store is byte for byte what it was.
//
// Runs only inside tests/support/in-private-netns (CVO_PRIVATE_NETNS=1): lo alone.
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/store/store_records.hpp"
#include "tests/backendd/netns_support.hpp"
#include "tests/backendd/tracker_recording.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::Captured;
using cvo::testing::LcmCapture;

const fs::path kSample = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";
constexpr double kPeriod = 1.0 / 30;

// A TUM folder of the sample's frames `indices` (-1: a frame whose depth is all zeros), stamped
// anew from the first one's time at 30 Hz.
fs::path write_folder(const fs::path& folder, const std::vector<int>& indices) {
  const auto sample = io::TumSequence::open(kSample);
  fs::create_directories(folder);
  const auto& files = sample.files();
  const fs::path blank = folder / "blank_depth.png";
  cv::imwrite(blank.string(), cv::Mat(480, 640, CV_16UC1, cv::Scalar(0)));
  std::ofstream rgb(folder / "rgb.txt"), depth(folder / "depth.txt");
  rgb << std::fixed << std::setprecision(6);
  depth << std::fixed << std::setprecision(6);
  for (std::size_t n = 0; n < indices.size(); ++n) {
    const double t = files.front().timestamp + static_cast<double>(n) * kPeriod;
    const auto& f = files.at(static_cast<std::size_t>(std::max(indices[n], 0)));
    rgb << t << " " << fs::absolute(f.rgb).string() << "\n";
    depth << t << " " << (indices[n] < 0 ? blank : fs::absolute(f.depth)).string() << "\n";
  }
  return folder;
}

std::vector<int> range(int first, int last) {
  std::vector<int> out;
  for (int i = first; i <= last; ++i) out.push_back(i);
  return out;
}

// The stored map: cvo-backendd in mapping mode over a file:// recording of a live tracker.
fs::path map_by_the_daemon(const fs::path& dir) {
  const auto folder = write_folder(dir / "fr1_first_half", range(0, 24));
  cvo::testing::tracker_recording(dir, {}, folder);
  const auto store = dir / "map.store";
  cvo::testing::DaemonProcess backendd(fs::path(CVO_TOOLS_DIR) / "cvo-backendd",
                                       {"--lcm-url", "file://" + (dir / "tracker.lcmlog").string() + "?speed=0",
                                        "--publish-url", "memq://", "--store", store.string(), "--exit-on-eof"},
                                       dir / "mapping.txt");
  EXPECT_EQ(backendd.wait_for(120s).value_or(-9), 0) << cvo::testing::slurp(dir / "mapping.txt");
  return store;
}

// The stored map made offline: cvo-run --mode slam --store.
fs::path map_by_cvo_run(const fs::path& dir) {
  const auto folder = write_folder(dir / "fr1_first_half", range(0, 24));
  const auto store = dir / "offline.store";
  const auto run = cvo::testing::run_tool("cvo-run",
                                          cvo::testing::quoted(folder.string()) + " --mode slam --out " +
                                              cvo::testing::quoted((dir / "first.txt").string()) + " --store " +
                                              cvo::testing::quoted(store.string()),
                                          dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return store;
}

// The visitor through both daemons in the map of `store`: its states on CVO_POSE, the store unchanged.
void localize_through_the_daemons(const fs::path& dir, const fs::path& store) {
  const auto before = cvo::testing::slurp(store);
  ASSERT_GT(before.size(), 1000u);

  std::vector<int> frames = range(25, 49);
  frames.push_back(-1);  // the camera covered: no depth, the odometry fails at the next frame
  for (const int i : range(0, 49)) frames.push_back(i);
  const auto visitor = write_folder(dir / "fr1_visitor", frames);

  LcmCapture capture(dir / "maps.lcmlog");
  ASSERT_TRUE(capture.good());
  const auto backend_log = dir / "localization.txt";
  auto backendd = cvo::testing::start_backendd(store, backend_log, {"backendd.mode=localization"});
  const int pid = backendd->pid();
  ASSERT_TRUE(capture.wait_until([&](const Captured& c) { return c.status_from(pid) && c.map.has_value(); }, 120s))
      << cvo::testing::slurp(backend_log);
  auto trackerd = cvo::testing::start_trackerd(visitor, dir / "tracker_live.txt", true);
  EXPECT_EQ(trackerd.wait_for(120s).value_or(-9), 0) << cvo::testing::slurp(dir / "tracker_live.txt");
  EXPECT_EQ(cvo::testing::stop(*backendd, 120s).value_or(-9), 0) << cvo::testing::slurp(backend_log);

  const Captured c = capture.snapshot();
  const std::string logs = cvo::testing::slurp(backend_log) + cvo::testing::slurp(dir / "tracker_live.txt");
  ASSERT_EQ(c.state_changes.size(), 2u) << logs;  // two tracker sessions
  const auto& first = c.state_changes.at(0).second;
  const auto& second = c.state_changes.at(1).second;
  using P = cvo_lcm::pose_t;
  EXPECT_EQ(first, (std::vector<std::int8_t>{P::STATE_LOCALIZING, P::STATE_LOCALIZED, P::STATE_LOST})) << logs;
  EXPECT_EQ(second, (std::vector<std::int8_t>{P::STATE_LOCALIZING, P::STATE_LOCALIZED})) << logs;
  EXPECT_NE(logs.find("lost at frame 26"), std::string::npos) << logs;
  EXPECT_NE(logs.find("localized in the stored map"), std::string::npos) << logs;
  EXPECT_TRUE(cvo::testing::slurp(store) == before) << "the stored map changed";
}

TEST(BackenddLocalization, StatesReachCvoPoseAndTheStoredMapIsUnchanged) {
  if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
  const cvo::test::TempDir dir("cvo_localization");
  localize_through_the_daemons(dir.path(), map_by_the_daemon(dir.path()));
}

TEST(BackenddLocalization, AMapMadeOfflineByCvoRunServesTheDaemon) {
  if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
  const cvo::test::TempDir dir("cvo_localization_offline");
  localize_through_the_daemons(dir.path(), map_by_cvo_run(dir.path()));
}

}  // namespace
}  // namespace cvo::daemon
