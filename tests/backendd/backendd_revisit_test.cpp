// Revisits that do not grow cvo-backendd's store (issue 27 item 3): two tracker sessions of the
// embedded sample (a robot that comes back to what it saw) through the daemon. The second visit's
// keyframes are merged into the first's as they come: each merge is stored after its keyframe's
// record, which is then garbage and compacted away, so the store holds little more than one visit;
// a restart replays that store (merged keyframes from their merge records alone) to the same map.
//
// No network: the input is a log and the output another (file:// providers both ways).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <lcm/lcm-cpp.hpp>

#include "libcvo/store/merge_record.hpp"
#include "libcvo/store/store_records.hpp"
#include "tests/backendd/tracker_recording.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/lcm_log.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using store::RecordKind;

void write_log(const fs::path& file, const std::vector<std::vector<testing::Message>>& visits) {
  ::lcm::LogFile log(file.string(), "w");
  std::int64_t t = 0;
  for (const auto& visit : visits)
    for (const auto& m : visit) testing::write_event(log, m.channel, m.bytes, t += 1000);
}

struct BackendRun {
  std::string notes;
  cvo_lcm::map_t map;  // the final CVO_MAP
};

// cvo-backendd on `input` with its store at `store`, worked through to the end.
BackendRun backend(const fs::path& dir, const std::string& name, const fs::path& input, const fs::path& store) {
  const auto out = dir / (name + ".out.lcmlog");
  testing::DaemonProcess backendd(fs::path(CVO_TOOLS_DIR) / "cvo-backendd",
                                  {"--lcm-url", "file://" + input.string() + "?speed=0", "--publish-url",
                                   "file://" + out.string() + "?mode=w", "--store", store.string(), "--exit-on-eof"},
                                  dir / (name + ".txt"));
  BackendRun r;
  const int status = backendd.wait_for(600s).value_or(-9);
  r.notes = testing::slurp(dir / (name + ".txt"));
  EXPECT_EQ(status, 0) << r.notes;
  const auto published = testing::read_published(out);
  EXPECT_FALSE(published.maps.empty()) << r.notes;
  if (!published.maps.empty()) r.map = published.maps.back();
  return r;
}

// The store's keyframe records whose keyframe no merge record names (live ones), its merges and
// its settled records.
struct StoreCounts {
  std::size_t live = 0, merges = 0, settled = 0;
};
StoreCounts live_keyframes_and_merges(const fs::path& store) {
  const auto snapshot = store::read_store(store);
  EXPECT_TRUE(snapshot.scan.clean());
  std::set<std::pair<std::int64_t, std::int64_t>> merged;
  std::size_t keyframes = 0, settled = 0;
  std::vector<std::pair<std::int64_t, std::int64_t>> kept;
  for (const auto& r : snapshot.scan.records) {
    const std::uint8_t* payload = snapshot.payload(r);
    const auto bytes = store::StoreSnapshot::payload_bytes(r);
    if (r.kind == RecordKind::kMerge) {
      std::string error;
      const auto m = store::decode_merge(payload, bytes, &error);
      EXPECT_TRUE(m) << error;
      if (m) merged.insert({m->session, m->id});
    } else if (r.kind == RecordKind::kSettled) {
      ++settled;
    } else if (r.kind == RecordKind::kKeyframe) {
      cvo_lcm::keyframe_t k;
      EXPECT_GE(k.decode(payload, 0, static_cast<int>(bytes)), 0);
      kept.push_back({k.session, k.id});
    }
  }
  for (const auto& k : kept) keyframes += !merged.contains(k);
  return {keyframes, merged.size(), settled};
}

TEST(BackenddRevisit, ASecondVisitIsMergedIntoTheFirstAndARestartReplaysTheSameMap) {
  const test::TempDir dir("backendd_revisit");
  fs::create_directories(dir.path() / "first");
  fs::create_directories(dir.path() / "second");
  const auto first = testing::tracker_recording(dir.path() / "first");
  const auto second = testing::tracker_recording(dir.path() / "second");
  ASSERT_FALSE(first.empty());
  write_log(dir.path() / "one.lcmlog", {first});
  write_log(dir.path() / "two.lcmlog", {first, second});

  const auto one_store = dir.path() / "one.store", two_store = dir.path() / "two.store";
  const BackendRun one = backend(dir.path(), "one", dir.path() / "one.lcmlog", one_store);
  const BackendRun two = backend(dir.path(), "two", dir.path() / "two.lcmlog", two_store);
  const auto [live_one, merges_one, settled_one] = live_keyframes_and_merges(one_store);
  const auto [live_two, merges_two, settled_two] = live_keyframes_and_merges(two_store);
  std::printf(
      "one visit: %zu keyframes, store %ju bytes; two visits: %zu live keyframe records, %zu merges, %zu settled "
      "records, store %ju bytes; final map %d keyframes\n",
      live_one, static_cast<std::uintmax_t>(fs::file_size(one_store)), live_two, merges_two, settled_two,
      static_cast<std::uintmax_t>(fs::file_size(two_store)), two.map.num_keyframes);
  EXPECT_EQ(merges_one, 0u);
  ASSERT_EQ(two.map.num_sessions, 2);
  EXPECT_TRUE(two.map.sessions[0].placed && two.map.sessions[1].placed);
  // At most a fifth of the first visit's keyframes are added by the second (without merges: all).
  EXPECT_LE(5 * (live_two - live_one), live_one);
  // The second visit's keyframes are merged: the map leaves them out. Those settled (slam::Mapper::settle)
  // left settled records instead of their merge and local-graph records: few merges stay.
  EXPECT_LE(static_cast<std::size_t>(two.map.num_keyframes), live_two + 1);
  EXPECT_EQ(settled_one, 0u);
  EXPECT_GT(settled_two, 0u);
  EXPECT_LT(merges_two, live_one / 2);
  // What lives is little more than one visit, and garbage is compacted once past a quarter of the
  // file (so the file is within 4/3 of what lives): below 1.4 times one visit (without merges: 2).
  EXPECT_LT(fs::file_size(two_store), fs::file_size(one_store) * 7 / 5);
  EXPECT_NE(two.notes.find("store compacted"), std::string::npos) << two.notes;
  // Its join is told though the map lists none of the second visit's keyframes (all merged).
  EXPECT_NE(two.notes.find("joined the map at its keyframe"), std::string::npos) << two.notes;
  EXPECT_EQ(two.notes.find("nan s"), std::string::npos) << two.notes;

  // Restarted on that store (nothing new comes): the same keyframes, at the same poses.
  const std::vector<std::uint8_t> nothing{0};
  {
    ::lcm::LogFile quiet((dir.path() / "quiet.lcmlog").string(), "w");
    testing::write_event(quiet, "CVO_TEST_NOTHING", nothing, 1);
  }
  const auto before = fs::file_size(two_store);
  const BackendRun again = backend(dir.path(), "again", dir.path() / "quiet.lcmlog", two_store);
  EXPECT_EQ(again.notes.find("not applied"), std::string::npos) << again.notes;
  ASSERT_EQ(again.map.num_keyframes, two.map.num_keyframes) << again.notes;
  for (int s = 0; s < two.map.num_sessions; ++s)  // forgotten keyframes counted still (tally records)
    EXPECT_EQ(again.map.sessions[static_cast<std::size_t>(s)].keyframes,
              two.map.sessions[static_cast<std::size_t>(s)].keyframes);
  EXPECT_LE(fs::file_size(two_store), before) << "a replay adds nothing to the store";
  double worst_m = 0, worst_deg = 0;
  for (std::size_t i = 0; i < two.map.keyframes.size(); ++i) {
    const auto& a = two.map.keyframes[i].pose;
    const auto& b = again.map.keyframes[i].pose;
    EXPECT_EQ(two.map.keyframes[i].id, again.map.keyframes[i].id);
    const Eigen::Vector3d ta(a.position[0], a.position[1], a.position[2]),
        tb(b.position[0], b.position[1], b.position[2]);
    const Eigen::Quaterniond qa(a.orientation[0], a.orientation[1], a.orientation[2], a.orientation[3]);
    const Eigen::Quaterniond qb(b.orientation[0], b.orientation[1], b.orientation[2], b.orientation[3]);
    worst_m = std::max(worst_m, (ta - tb).norm());
    worst_deg = std::max(worst_deg, qa.angularDistance(qb) * 180 / M_PI);
  }
  std::printf("replayed map: keyframes within %.3f mm and %.4f deg of the live one\n", 1e3 * worst_m, worst_deg);
  EXPECT_LT(worst_m, 0.005);
  EXPECT_LT(worst_deg, 0.5);
}

}  // namespace
}  // namespace cvo::daemon
