// cvo-backendd publishes the occupancy grid of its map on CVO_GRID: fed a real tracker's keyframes
// of a rendered room (an orbit that closes a loop), read from a file:// log with --exit-on-eof, it
// sends grids that decode and convert, each showing the CVO_MAP of its revision, at most once a
// second unless a loop closure moved keyframes, and a final one at shutdown that shows the final map.
//
// No network: the input is a log and the output another (file:// providers both ways).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/grid_t.hpp"
#include "cvo_lcm/map_t.hpp"
#include "libcvo/lcm/grid_conversion.hpp"
#include "libcvo/sim/sequence.hpp"
#include "tests/backendd/tracker_recording.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/lcm_log.hpp"
#include "tests/support/loop_orbit.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::DaemonProcess;

void write_log(const fs::path& file, const std::vector<cvo::testing::Message>& messages) {
  ::lcm::LogFile log(file.string(), "w");
  std::int64_t t = 0;
  for (const auto& m : messages) cvo::testing::write_event(log, m.channel, m.bytes, t += 1000);
}

struct Outcome {
  int exit_code = -1;
  std::string log;
  cvo::testing::PublishedLog published;
};

Outcome run_backendd(const fs::path& dir, const std::string& name, const std::vector<cvo::testing::Message>& messages) {
  const auto input = dir / (name + ".lcmlog"), out = dir / (name + ".out.lcmlog");
  write_log(input, messages);
  DaemonProcess backendd(
      fs::path(CVO_TOOLS_DIR) / "cvo-backendd",
      {"--lcm-url", "file://" + input.string() + "?speed=0", "--publish-url", "file://" + out.string() + "?mode=w",
       "--store", (dir / (name + ".store")).string(), "--exit-on-eof",
       // A CVO_MAP after every change, so that what paces the grids is the grid's own second.
       "--set", "backendd.map_period_s=0"},
      dir / (name + ".txt"));
  Outcome r;
  r.exit_code = backendd.wait_for(600s).value_or(-9);
  r.log = cvo::testing::slurp(dir / (name + ".txt"));
  r.published = cvo::testing::read_published(out);
  return r;
}

class BackenddGrid : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir("backendd_grid");
    const auto messages =
        cvo::testing::tracker_recording(dir_->path(), {}, cvo::testing::write_loop_orbit(dir_->path()));
    run_ = new Outcome(run_backendd(dir_->path(), "tracked", messages));
  }
  static void TearDownTestSuite() {
    delete run_;
    delete dir_;
  }
  static const Outcome& run() { return *run_; }

 private:
  static inline test::TempDir* dir_ = nullptr;
  static inline Outcome* run_ = nullptr;
};

// The maps published, by revision.
std::map<std::int64_t, const cvo_lcm::map_t*> maps_by_revision(const Outcome& run) {
  std::map<std::int64_t, const cvo_lcm::map_t*> out;
  for (const auto& m : run.published.maps) out[m.revision] = &m;
  return out;
}

TEST_F(BackenddGrid, EveryGridDecodesAndIsAGridOfTheRoom) {
  ASSERT_EQ(run().exit_code, 0) << run().log;
  const auto& grids = run().published.grids;
  EXPECT_EQ(run().published.undecodable, 0);
  ASSERT_GE(grids.size(), 2u) << "a first grid and a final one\n" << run().log;
  for (const auto& g : grids) {
    std::string error;
    const auto grid = lcm::from_message(g, &error);
    ASSERT_TRUE(grid) << error;
    EXPECT_EQ(g.frame, "grid");
    EXPECT_EQ(g.up, +cvo_lcm::grid_t::UP_FLOOR_PLANE) << "no mount configured, no accelerometer on CVO_KEYFRAME";
    EXPECT_EQ(g.resolution, 0.05) << "mapping.cell_size's default";
  }
  // The final grid shows the room: its walls occupied, the floor in between free.
  const auto& last = grids.back();
  std::size_t occupied = 0, free = 0;
  for (const auto c : last.cells)
    occupied += c == cvo_lcm::grid_t::CELL_OCCUPIED, free += c == cvo_lcm::grid_t::CELL_FREE;
  EXPECT_GT(occupied, 50u);
  EXPECT_GT(free, 200u);
  std::printf("CVO_GRID: %zu sent; the last %d x %d cells, %d bytes encoded, %zu occupied, %zu free\n", grids.size(),
              last.width, last.height, last.getEncodedSize(), occupied, free);
}

TEST_F(BackenddGrid, EachGridShowsTheMapOfItsRevisionAndTheLastTheFinalMap) {
  ASSERT_EQ(run().exit_code, 0) << run().log;
  const auto& grids = run().published.grids;
  ASSERT_FALSE(grids.empty()) << run().log;
  ASSERT_FALSE(run().published.maps.empty());
  const auto maps = maps_by_revision(run());
  for (const auto& g : grids) {
    EXPECT_TRUE(maps.count(g.revision)) << "grid of revision " << g.revision << ": no CVO_MAP of it";
    EXPECT_EQ(g.epoch, run().published.maps.front().epoch);
  }
  for (std::size_t i = 1; i < grids.size(); ++i) EXPECT_GE(grids[i].revision, grids[i - 1].revision);
  EXPECT_EQ(grids.back().revision, run().published.maps.back().revision) << "the final grid is of the final map";
  EXPECT_NE(run().log.find("CVO_GRIDs sent"), std::string::npos) << run().log;
}

// Whether some keyframe of `before` is at least (about) half a cell or half a degree from where
// `now` has it.
bool moved_visibly(const cvo_lcm::map_t& before, const cvo_lcm::map_t& now) {
  std::map<std::pair<std::int64_t, std::int64_t>, const cvo_lcm::pose3d_t*> at;
  for (const auto& k : now.keyframes) at[{k.session, k.id}] = &k.pose;
  for (const auto& k : before.keyframes) {
    const auto it = at.find({k.session, k.id});
    if (it == at.end()) continue;
    double d2 = 0, dot = 0;
    for (int c = 0; c < 3; ++c) d2 += std::pow(k.pose.position[c] - it->second->position[c], 2);
    for (int c = 0; c < 4; ++c) dot += k.pose.orientation[c] * it->second->orientation[c];
    const double angle = 2 * std::acos(std::min(1.0, std::abs(dot)));
    if (std::sqrt(d2) >= 0.9 * 0.025 || angle >= 0.9 * 0.5 * M_PI / 180) return true;
  }
  return false;
}

struct Pacing {
  int paced = 0;    // grids a second or more after the one before
  int at_once = 0;  // grids less than a second after the one before, after a loop that moved keyframes
  int loops = 0;    // grids after a loop that moved keyframes
};

// At most once a second, unless a loop closure moved keyframes of the previous grid visibly (its
// grid may go out at once); the final one at shutdown comes when it comes.
Pacing expect_paced(const Outcome& run) {
  const auto& grids = run.published.grids;
  const auto maps = maps_by_revision(run);
  Pacing p;
  for (std::size_t i = 1; i + 1 < grids.size(); ++i) {
    const auto gap_s = static_cast<double>(grids[i].utime - grids[i - 1].utime) * 1e-6;
    if (!maps.count(grids[i].revision) || !maps.count(grids[i - 1].revision)) {
      ADD_FAILURE() << "no CVO_MAP of grid " << i << "'s revision";
      continue;
    }
    const auto& before = *maps.at(grids[i - 1].revision);
    const auto& now = *maps.at(grids[i].revision);
    if (now.num_loops > before.num_loops && moved_visibly(before, now)) {
      ++p.loops;
      p.at_once += gap_s < 0.99;
      continue;
    }
    ++p.paced;
    EXPECT_GE(gap_s, 0.99) << "grid " << i << " of revision " << grids[i].revision;
  }
  std::printf(
      "%zu grids: %d paced, %d after a loop that moved keyframes (%d less than a second after the one "
      "before), and the final one\n",
      grids.size(), p.paced, p.loops, p.at_once);
  return p;
}

TEST_F(BackenddGrid, GridsComeAtMostOnceASecondWhileTheMapGrows) {
  ASSERT_EQ(run().exit_code, 0) << run().log;
  ASSERT_GE(run().published.grids.size(), 3u) << run().log;
  const Pacing p = expect_paced(run());
  EXPECT_GT(p.paced, 0) << "the run lasts seconds: some grids wait for their second\n" << run().log;
}

}  // namespace
}  // namespace cvo::daemon
