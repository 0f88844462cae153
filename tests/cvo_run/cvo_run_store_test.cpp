// cvo-run --mode slam --store FILE writes the keyframe store cvo-backendd would write: cvo-map
// reads it (every record intact, one session per folder, all in the map), a real cvo-backendd
// started on it replays it (its final CVO_MAP holds every keyframe cvo-run made, in the map) and
// leaves it as it was; the same input writes the same bytes, and a store that exists already is not touched.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "libcvo/store/store_records.hpp"
#include "tests/drivers/tum_copy.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/lcm_log.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using store::RecordKind;
using testing::json_value;
using testing::quoted;
using testing::run_tool;
using testing::slurp;
using testing::ToolRun;

// The number after `label` in a tool's text ("records: 17 intact" -> 17), -1 when absent.
long number_after(const std::string& text, const std::string& label) {
  std::smatch m;
  if (!std::regex_search(text, m, std::regex(label + " ?([0-9]+)"))) return -1;
  return std::stol(m[1]);
}

// The two halves of the embedded sample, as two folders (two sessions of one map).
std::vector<fs::path> halves(const fs::path& dir) {
  test::write_tum_copy(dir / "fr1_first", 25);
  test::write_tum_copy(dir / "fr1_second", 25, std::nullopt, 25);
  return {dir / "fr1_first", dir / "fr1_second"};
}

ToolRun slam_with_store(const std::vector<fs::path>& folders, const fs::path& store, const fs::path& dir) {
  std::string args;
  for (const auto& f : folders) args += quoted(f) + " ";
  return run_tool(
      "cvo-run", args + "--mode slam --out " + quoted(dir / "slam.txt") + " --store " + quoted(store) + " --json", dir);
}

TEST(CvoRunStore, CvoMapReadsTheStoreOfATwoSessionRun) {
  const test::TempDir dir("cvo_run_store");
  const auto store = dir.path() / "map.store";
  const ToolRun r = slam_with_store(halves(dir.path()), store, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const long keyframes = std::stol(json_value(r.out, "keyframes"));
  const long records = std::stol(json_value(r.out, "records"));
  const long merged = std::stol(json_value(r.out, "keyframes_merged"));  // the second half may start covered
  // A keyframe and its local graph each; a merge record and the tombstone of its keyframe's record
  // for each merge.
  EXPECT_EQ(records, 2 * keyframes + 2 * merged);

  // The records are the daemon's: CVO_KEYFRAME and CVO_LOCAL_GRAPH payloads, one session per folder.
  const auto scan = store::read_store(store).scan;
  EXPECT_TRUE(scan.clean());
  EXPECT_EQ(static_cast<long>(scan.records.size()), 2 * keyframes) << "each merge record replaces its keyframe's";
  EXPECT_EQ(scan.records.front().kind, RecordKind::kKeyframe);

  const ToolRun map = run_tool("cvo-map", quoted(store) + " --out " + quoted(dir.path() / "map"), dir.path());
  ASSERT_EQ(map.exit_code, 0) << map.err;
  EXPECT_NE(map.out.find("records: " + std::to_string(2 * keyframes) + " intact, 0 skipped; no damage"),
            std::string::npos)
      << map.out;
  EXPECT_EQ(number_after(map.out, "map:"), keyframes - merged) << map.out;
  EXPECT_NE(map.out.find("2 of 2 sessions in the map"), std::string::npos) << map.out << map.err;
}

// Five visits of the sample (issue #27 item 3): the revisits' keyframes are merged into the first
// visit's, each merge a small record after the keyframe's, and the merged keyframes' records are
// compacted away (keyframe_store.hpp): the store holds at most 4/3 of its live records, and
// cvo-map replays it, merged keyframes from their merge records alone, to the map cvo-run made.
TEST(CvoRunStore, RevisitsAreMergedAndTheirKeyframeRecordsCompactedAway) {
  const test::TempDir dir("cvo_run_store_revisits");
  const auto store = dir.path() / "map.store";
  const fs::path sample = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";
  const ToolRun r = slam_with_store({sample, sample, sample, sample, sample}, store, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const long keyframes = std::stol(json_value(r.out, "keyframes"));
  const long merged = std::stol(json_value(r.out, "keyframes_merged"));
  ASSERT_GT(merged, 0);

  const auto scan = store::read_store(store).scan;
  EXPECT_TRUE(scan.clean());
  long keyframe_records = 0, merge_records = 0;
  for (const auto& record : scan.records) {
    keyframe_records += record.kind == RecordKind::kKeyframe;
    merge_records += record.kind == RecordKind::kMerge;
  }
  EXPECT_EQ(merge_records, merged);
  EXPECT_LT(keyframe_records, keyframes);  // merged keyframes' records are gone, but for garbage below a quarter:
  EXPECT_LE(3 * keyframe_records, 4 * (keyframes - merged));
  std::printf("5 visits: %ld keyframes, %ld merged, %ld keyframe records kept, store %zu bytes\n", keyframes, merged,
              keyframe_records, static_cast<std::size_t>(fs::file_size(store)));

  const ToolRun map = run_tool("cvo-map", quoted(store) + " --out " + quoted(dir.path() / "map"), dir.path());
  ASSERT_EQ(map.exit_code, 0) << map.err;
  EXPECT_NE(map.out.find("5 of 5 sessions in the map"), std::string::npos) << map.out << map.err;
  EXPECT_EQ(map.err.find("not applied"), std::string::npos) << map.err;
}

// A local graph is stamped with its sensor time, not the wall clock's: a map made again is the same file.
TEST(CvoRunStore, TheSameInputWritesTheSameStore) {
  const test::TempDir dir("cvo_run_store_same");
  test::write_tum_copy(dir.path() / "fr1_first", 25);
  ASSERT_EQ(slam_with_store({dir.path() / "fr1_first"}, dir.path() / "a.store", dir.path()).exit_code, 0);
  ASSERT_EQ(slam_with_store({dir.path() / "fr1_first"}, dir.path() / "b.store", dir.path()).exit_code, 0);
  EXPECT_GT(fs::file_size(dir.path() / "a.store"), 8u);
  EXPECT_TRUE(slurp(dir.path() / "a.store") == slurp(dir.path() / "b.store"));
}

// A log with one event on a channel nobody reads: the file:// provider needs a first event.
fs::path quiet_log(const fs::path& file) {
  ::lcm::LogFile log(file.string(), "w");
  EXPECT_EQ(testing::write_event(log, "CVO_TEST_NOTHING", {0}, 1), 0);
  return file;
}

TEST(CvoRunStore, ACvoBackenddStartedOnTheStoreReplaysIt) {
  const test::TempDir dir("cvo_run_store_backendd");
  const auto store = dir.path() / "state" / "keyframes.store";
  fs::create_directories(store.parent_path());
  const ToolRun r = slam_with_store({test::kSample}, store, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const long keyframes = std::stol(json_value(r.out, "keyframes"));
  const std::string before = slurp(store);

  const auto published = dir.path() / "published.lcmlog";
  testing::DaemonProcess backendd(
      fs::path(CVO_TOOLS_DIR) / "cvo-backendd",
      {"--lcm-url", "file://" + quiet_log(dir.path() / "in.lcmlog").string(), "--publish-url",
       "file://" + published.string() + "?mode=w", "--store", store.string(), "--exit-on-eof"},
      dir.path() / "backend.txt");
  ASSERT_EQ(backendd.wait_for(120s).value_or(-9), 0) << slurp(dir.path() / "backend.txt");
  const std::string note = slurp(dir.path() / "backend.txt");
  EXPECT_NE(note.find("(" + std::to_string(2 * keyframes) + " records recovered)"), std::string::npos) << note;

  const auto log = testing::read_published(published);
  ASSERT_FALSE(log.maps.empty()) << note;
  const auto& map = log.maps.back();
  ASSERT_EQ(map.num_sessions, 1);
  EXPECT_EQ(map.sessions[0].session, 1) << "cvo-run numbers its sessions 1, 2, ...";
  EXPECT_TRUE(map.sessions[0].placed);
  EXPECT_EQ(map.num_keyframes, keyframes);
  EXPECT_TRUE(slurp(store) == before) << "the daemon found nothing to repair or add";
}

TEST(CvoRunStore, AStoreThatExistsIsLeftAloneAndOnlySlamModeStores) {
  const test::TempDir dir("cvo_run_store_refused");
  const auto store = dir.write("robot.store", "a robot's map");
  const ToolRun exists = slam_with_store({test::kSample}, store, dir.path());
  EXPECT_EQ(exists.exit_code, 1) << exists.err;
  EXPECT_NE(exists.err.find(store.string()), std::string::npos) << exists.err;
  EXPECT_NE(exists.err.find("exists already"), std::string::npos) << exists.err;
  EXPECT_EQ(slurp(store), "a robot's map");

  const ToolRun kf = run_tool("cvo-run",
                              quoted(test::kSample) + " --mode kf-cvo --out " + quoted(dir.path() / "t.txt") +
                                  " --store " + quoted(dir.path() / "new.store"),
                              dir.path());
  EXPECT_EQ(kf.exit_code, 2) << kf.err;
  EXPECT_NE(kf.err.find("--store"), std::string::npos) << kf.err;
  EXPECT_FALSE(fs::exists(dir.path() / "new.store"));
}

}  // namespace
}  // namespace cvo
