// One map through two tracker sessions, the way a robot's tracker restarts: cvo-trackerd runs on
// frames 0-249 of TUM fr1/rpy and is killed (SIGKILL), a new cvo-trackerd runs on the rest (frames
// 250-474), and one cvo-backendd takes both over real LCM UDP multicast. The back end must join the
// second session to the first (both placed in its last CVO_MAP, loops between them), and the map's
// ATE over both sessions (cvo-log map, cvo-eval) must stay within 1.5x of the same daemons on every
// frame as one session. Run with the back end up throughout (one robot's tracker restarted), and
// with the back end killed (SIGKILL) and restarted between the sessions, which must resume both
// from its store; there the second session is another robot's, and the map names each session's
// robot (the first's from the store) and reports the loops between the two robots.
//
// Needs ../shared/data/tum/fr1_rpy (skips with a message without it). Runs only inside
// tests/support/in-private-netns (CVO_PRIVATE_NETNS=1): lo alone, no packet can leave the host.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/core/session.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/slam/mapper.hpp"
#include "tests/backendd/netns_support.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::Captured;
using cvo::testing::DaemonProcess;
using cvo::testing::KeyframeName;
using cvo::testing::LcmCapture;

const fs::path kSequence = (fs::path(CVO_SHARED_DATA_DIR) / "tum" / "fr1_rpy").lexically_normal();
// The frame the second session starts at: frames as the tracker numbers them (colour images with a
// depth image within 20 ms; fr1/rpy's 500 colour images make 475).
constexpr std::size_t kSecondSession = 250;

// Frames [first, first + count) of the sequence as a TUM folder of their own: index files naming
// the original images by absolute path, the full ground truth. Named fr1_... for the camera preset.
fs::path write_part(const fs::path& folder, std::size_t first, std::size_t count) {
  const auto sequence = io::TumSequence::open(kSequence);
  fs::create_directories(folder);
  std::ofstream rgb(folder / "rgb.txt"), depth(folder / "depth.txt");
  rgb << std::fixed << std::setprecision(6);
  depth << std::fixed << std::setprecision(6);
  for (std::size_t i = first; i < first + count; ++i) {
    const auto& f = sequence.files().at(i);
    rgb << f.timestamp << " " << fs::absolute(f.rgb).string() << "\n";
    depth << f.depth_timestamp << " " << fs::absolute(f.depth).string() << "\n";
  }
  fs::copy_file(kSequence / "groundtruth.txt", folder / "groundtruth.txt");
  return folder;
}

struct Leg {
  fs::path folder;
  std::size_t frames = 0;
  bool killed = false;  // SIGKILL after its last frame's pose (else it exits at the end of its frames)
  std::string robot = "hall-a";
};

struct MapRun {
  Captured captured;
  std::vector<std::int64_t> sessions;  // the trackers' sessions, in order
  std::string backend_log;             // every back-end instance's stderr
  double ate = 0;
  std::string map_log;  // what cvo-log map said
};

class BackenddSessions : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
    if (!fs::exists(kSequence / "rgb.txt"))
      GTEST_SKIP() << "skipped: needs TUM fr1/rpy at " << kSequence << " (the shared data folder is not here)";
    frames_ = io::TumSequence::open(kSequence).size();
    ASSERT_GT(frames_, kSecondSession + 100);
  }

  // One tracker session: started once the back end receives, run over its frames, then killed
  // or left to exit; returns its session.
  static std::int64_t run_leg(const Leg& leg, LcmCapture& capture, const fs::path& stderr_file) {
    const auto before = capture.snapshot().last_frame;  // earlier sessions
    auto trackerd = cvo::testing::start_trackerd(leg.folder, stderr_file, !leg.killed, {"trackerd.robot=" + leg.robot});
    std::int64_t session = 0;
    const auto last = static_cast<std::int64_t>(leg.frames) - 1;
    const bool tracked = capture.wait_until(
        [&](const Captured& c) {
          for (const auto& [s, frame] : c.last_frame)
            if (frame == last && !before.count(s)) session = s;
          return session != 0;
        },
        300s);
    EXPECT_TRUE(tracked) << "cvo-trackerd did not track " << leg.folder << "\n" << cvo::testing::slurp(stderr_file);
    if (leg.killed) {
      trackerd.signal(SIGKILL);
      trackerd.wait_for(5s);
    } else {
      EXPECT_EQ(trackerd.wait_for(60s).value_or(-9), 0) << cvo::testing::slurp(stderr_file);
    }
    return session;
  }

  // The back end over every leg in order (killed and restarted between legs when asked), stopped
  // with SIGTERM at the end; the ATE of its last map.
  static MapRun run_map(const fs::path& dir, const std::string& name, const std::vector<Leg>& legs,
                        bool restart_between) {
    MapRun run;
    const auto store = dir / (name + ".store");
    const auto maps = dir / (name + ".lcmlog");
    auto capture_owner = std::make_unique<LcmCapture>(maps);  // closed (its log complete) before cvo-log reads it
    LcmCapture& capture = *capture_owner;
    EXPECT_TRUE(capture.good());
    int instance = 0;
    std::vector<fs::path> logs;
    std::unique_ptr<DaemonProcess> backendd;
    const auto start = [&] {
      logs.push_back(dir / (name + ".backendd" + std::to_string(++instance) + ".txt"));
      backendd = cvo::testing::start_backendd(store, logs.back());
      const int pid = backendd->pid();
      EXPECT_TRUE(capture.wait_until([&](const Captured& c) { return c.status_from(pid); }, 120s))
          << cvo::testing::slurp(logs.back());
    };
    start();
    for (std::size_t i = 0; i < legs.size(); ++i) {
      run.sessions.push_back(run_leg(legs[i], capture, dir / (name + ".trackerd" + std::to_string(i + 1) + ".txt")));
      if (!restart_between || i + 1 == legs.size()) continue;
      // Killed once its map holds every keyframe of the session: all of them are in the store.
      const auto sent = capture.snapshot().keyframes_of(run.sessions.back());
      EXPECT_TRUE(capture.wait_until([&](const Captured& c) { return c.map_holds(sent); }, 300s))
          << cvo::testing::slurp(logs.back());
      backendd->signal(SIGKILL);
      backendd->wait_for(5s);
      start();
    }
    const int pid = backendd->pid();
    const auto code = cvo::testing::stop(*backendd, 600s);  // drains its queue, then the global optimisation
    EXPECT_EQ(code.value_or(-9), 0) << cvo::testing::slurp(logs.back());
    EXPECT_TRUE(capture.wait_until(
        [&](const Captured& c) { return c.status_from(pid, +cvo_lcm::status_t::STATE_STOPPING); }, 30s));
    for (const auto& log : logs) run.backend_log += cvo::testing::slurp(log);
    run.captured = capture.snapshot();
    capture_owner.reset();
    run.ate = ate(dir, maps, &run.map_log);
    return run;
  }

  // cvo-log map (what it says in *said), then cvo-eval against the sequence's ground truth.
  static double ate(const fs::path& dir, const fs::path& maps, std::string* said) {
    const auto trajectory = dir / (maps.stem().string() + ".txt");
    const auto log = cvo::testing::run_tool(
        "cvo-log", "map " + cvo::testing::quoted(maps) + " --out " + cvo::testing::quoted(trajectory), dir);
    EXPECT_EQ(log.exit_code, 0) << log.err;
    *said = log.err;
    const auto eval = cvo::testing::run_tool(
        "cvo-eval",
        cvo::testing::quoted(kSequence / "groundtruth.txt") + " " + cvo::testing::quoted(trajectory) + " --json", dir);
    EXPECT_EQ(eval.exit_code, 0) << eval.err;
    return cvo::testing::json_number(eval.out, "ate_rmse_m");
  }

  // Every frame as one session: the reference.
  [[nodiscard]] std::vector<Leg> whole(const fs::path& dir) const {
    return {{write_part(dir / "fr1_rpy_all", 0, frames_), frames_, false}};
  }
  // Frames 0-249, the tracker killed after them, then the rest by a new tracker (of `second_robot`).
  [[nodiscard]] std::vector<Leg> halves(const fs::path& dir, const std::string& second_robot = "hall-a") const {
    const std::size_t rest = frames_ - kSecondSession;
    return {{write_part(dir / "fr1_rpy_a", 0, kSecondSession), kSecondSession, true},
            {write_part(dir / "fr1_rpy_b", kSecondSession, rest), rest, false, second_robot}};
  }

  std::size_t frames_ = 0;

  // Both sessions in the last map, placed, with loops between them; every keyframe the trackers
  // sent; the ATE within 1.5x of one session's. Prints the figures.
  static void check_joined(const MapRun& two, const MapRun& one) {
    ASSERT_EQ(two.sessions.size(), 2u);
    ASSERT_TRUE(two.captured.map) << two.backend_log;
    const auto& last = *two.captured.map;
    ASSERT_EQ(last.sessions.size(), 2u) << two.backend_log;
    for (const auto& s : last.sessions)
      EXPECT_TRUE(s.placed) << core::session_name(s.session) << " unplaced\n" << two.backend_log;
    int across = 0;
    for (const auto& l : last.loops) across += l.from_session != l.to_session;
    EXPECT_GT(across, 0) << two.backend_log;
    std::string counts;  // what each session's entry holds against what its tracker sent
    for (const auto& e : last.sessions)
      counts += " " + core::session_name(e.session) + ": " + std::to_string(e.keyframes) + " of " +
                std::to_string(two.captured.keyframes_of(e.session).size());
    EXPECT_TRUE(two.captured.map_holds(two.captured.keyframes))
        << "keyframes the trackers sent are not in the map (held of sent):" << counts << "\n"
        << two.backend_log;
    for (const auto session : two.sessions) EXPECT_FALSE(two.captured.keyframes_of(session).empty());

    std::smatch join;
    const std::regex joined("session " + core::session_name(two.sessions[1]) + " joined the map at [^\n]*");
    EXPECT_TRUE(std::regex_search(two.backend_log, join, joined)) << two.backend_log;
    std::printf("two sessions: map ATE %.4f m (one session %.4f m), %d loops across sessions of %zu; %s\n", two.ate,
                one.ate, across, last.loops.size(), join.empty() ? "no join noted" : join.str().c_str());
    EXPECT_LE(two.ate, 1.5 * one.ate);
  }
};

TEST_F(BackenddSessions, ATrackerRestartIsASecondSessionJoinedToTheMap) {
  cvo::test::TempDir dir;
  const auto one = run_map(dir.path(), "one", whole(dir.path()), false);
  const auto two = run_map(dir.path(), "two", halves(dir.path()), false);
  check_joined(two, one);
  // One robot: both sessions are hall-a's, and no loop is between robots.
  ASSERT_TRUE(two.captured.map);
  EXPECT_EQ(two.captured.map->robots, (std::vector<std::string>{"hall-a", "hall-a"}));
  EXPECT_NE(two.map_log.find("robots: hall-a (2 sessions, 2 placed, "), std::string::npos) << two.map_log;
  EXPECT_NE(two.map_log.find("loops between robots: none"), std::string::npos) << two.map_log;
}

TEST_F(BackenddSessions, ABackEndRestartBetweenSessionsResumesBoth) {
  cvo::test::TempDir dir;
  const auto one = run_map(dir.path(), "one", whole(dir.path()), false);
  const auto two = run_map(dir.path(), "two", halves(dir.path(), "hall-b"), true);
  // Two back-end instances; the second found the first session in its store.
  std::vector<unsigned long> recovered;
  const std::regex records("\\((\\d+) records recovered\\)");
  const auto& log = two.backend_log;
  for (auto it = std::sregex_iterator(log.begin(), log.end(), records); it != std::sregex_iterator(); ++it)
    recovered.push_back(std::stoul((*it)[1]));
  ASSERT_EQ(recovered.size(), 2u) << two.backend_log;
  EXPECT_GE(recovered[1], two.captured.keyframes_of(two.sessions[0]).size()) << two.backend_log;
  check_joined(two, one);
  // Two robots: the first session's robot came back from the store, the loops between them are
  // reported as they are accepted, at the stop, and by cvo-log map.
  ASSERT_TRUE(two.captured.map);
  const auto& map = *two.captured.map;
  ASSERT_EQ(map.robots.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i)
    EXPECT_EQ(map.robots[i], map.sessions[i].session == two.sessions[0] ? "hall-a" : "hall-b");
  EXPECT_NE(log.find("between robots hall-b and hall-a"), std::string::npos) << log;
  const std::regex between("loops between robots: hall-a-hall-b ([0-9]+)");
  std::smatch at_stop, in_map;
  EXPECT_TRUE(std::regex_search(log, at_stop, between)) << log;
  ASSERT_TRUE(std::regex_search(two.map_log, in_map, between)) << two.map_log;
  EXPECT_GT(std::stoi(in_map[1]), 0);
  std::printf("two robots: %s\n", in_map.str().c_str());
}

}  // namespace
}  // namespace cvo::daemon
