// Issue 48 through the real cvo-backendd: tracker recordings of one scene spliced as the audit did
// (session A whole, B's first keyframe and local graph, all of C, the rest of B). C's first
// keyframe is merged into B's, then B's into one of A's: an alias left naming a node that had left
// the keyframe graph made every record after it fail with map::at, no map was published, and the
// stop died with SIGABRT (exit 134). B and C are recorded from the clip without its first two
// frames, so that their keyframes are not A's (identical ones tie, and the map's keyframe wins).
//
// No network: the input is a log and the output another (file:// providers both ways).
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "tests/backendd/tracker_recording.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/lcm_log.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Recording = std::vector<testing::Message>;

// A TUM list without its first `skip` entries (comments kept).
void copy_list(const fs::path& from, const fs::path& to, std::size_t skip) {
  std::ifstream in(from);
  std::ofstream out(to);
  for (std::string line; std::getline(in, line);) {
    if (!line.starts_with('#') && skip > 0) {
      --skip;
      continue;
    }
    out << line << '\n';
  }
}

// The embedded clip from its frame `skip` on: its images linked, its lists cut (`dir`'s name says
// fr1, which tells the tracker the camera).
fs::path clip_from(const fs::path& dir, std::size_t skip) {
  const fs::path clip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";
  fs::create_directories(dir);
  for (const char* linked : {"rgb", "depth", "groundtruth.txt"}) fs::create_symlink(clip / linked, dir / linked);
  for (const char* list : {"rgb.txt", "depth.txt"}) copy_list(clip / list, dir / list, skip);
  return dir;
}

// The audit's splice: A whole, B's first keyframe and first local graph, all of C, the rest of B.
Recording spliced(const Recording& a, const Recording& b, const Recording& c) {
  Recording out = a, rest;
  bool keyframe = false, graph = false;
  for (const auto& m : b) {
    bool& first = m.channel == "CVO_KEYFRAME" ? keyframe : graph;
    (first ? rest : out).push_back(m);
    first = true;
  }
  out.insert(out.end(), c.begin(), c.end());
  out.insert(out.end(), rest.begin(), rest.end());
  return out;
}

TEST(BackenddChainedMerge, SessionsWhoseFirstKeyframesMergeInAChainStopCleanlyWithEveryRecordApplied) {
  const test::TempDir dir("backendd_chained_merge");
  for (const char* sub : {"a", "b", "c"}) fs::create_directories(dir.path() / sub);
  const auto later = clip_from(dir.path() / "fr1_rpy_from_2", 2);
  const Recording a = testing::tracker_recording(dir.path() / "a");
  const Recording b = testing::tracker_recording(dir.path() / "b", {}, later);
  const Recording c = testing::tracker_recording(dir.path() / "c", {}, later);
  ASSERT_TRUE(!a.empty() && !b.empty() && !c.empty());
  const auto input = dir.path() / "spliced.lcmlog";
  {
    ::lcm::LogFile log(input.string(), "w");
    std::int64_t t = 0;
    for (const auto& m : spliced(a, b, c)) testing::write_event(log, m.channel, m.bytes, t += 1000);
  }

  const auto out = dir.path() / "backend.out.lcmlog";
  testing::DaemonProcess backendd(
      fs::path(CVO_TOOLS_DIR) / "cvo-backendd",
      {"--lcm-url", "file://" + input.string() + "?speed=0", "--publish-url", "file://" + out.string() + "?mode=w",
       "--store", (dir.path() / "backend.store").string(), "--exit-on-eof"},
      dir.path() / "backend.txt");
  const int status = backendd.wait_for(300s).value_or(-9);
  const std::string notes = testing::slurp(dir.path() / "backend.txt");
  EXPECT_EQ(status, 0) << notes;
  EXPECT_EQ(notes.find("after a failure"), std::string::npos) << notes;
  EXPECT_EQ(notes.find("not applied"), std::string::npos) << notes;
  const auto published = testing::read_published(out);
  ASSERT_FALSE(published.statuses.empty()) << notes;
  EXPECT_EQ(published.statuses.back().failed_frames, 0) << "records skipped after a failure";
  ASSERT_FALSE(published.maps.empty()) << notes;
  const auto& map = published.maps.back();
  ASSERT_EQ(map.num_sessions, 3) << notes;
  for (const auto& s : map.sessions) EXPECT_TRUE(s.placed) << "session " << s.session << "\n" << notes;
}

}  // namespace
}  // namespace cvo::daemon
