// cvo-map on a real back end's keyframe store: a rendered room tracked by cvo-trackerd and stored
// by cvo-backendd. With one keyframe record damaged in the middle it makes the map from every
// intact record (the damaged one alone is lost), the four files load, and the store is left
// byte for byte as it was; it reads a store the daemon is appending to; a missing or foreign
// store is bad input naming the file; the command line is the project's.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <yaml-cpp/yaml.h>

#include "libcvo/sim/sequence.hpp"
#include "libcvo/store/store_records.hpp"
#include "tests/support/cli_contract.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using store::RecordKind;
using testing::DaemonProcess;
using testing::quoted;
using testing::run_tool;
using testing::slurp;
using testing::ToolRun;

std::string bytes_of(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::set<std::string> names_in(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

// 6 s of an orbit through the rendered room at 10 Hz, half-size camera, exact depth, recorded as
// cvo-trackerd publishes it (CVO_KEYFRAME, CVO_LOCAL_GRAPH, ...) into a log; `paced`: at the
// recording's rate (the log's times are a live tracker's), else as fast as it can.
fs::path tracker_log(const fs::path& dir, bool paced = false) {
  sim::SequenceOptions options;
  options.path = sim::PathKind::orbit;
  options.frames = 60;
  options.rate_hz = 10.0;
  options.render.supersample = false;
  options.intrinsics = {262.5, 262.5, 159.25, 119.25, 320, 240, 5000.0};
  sim::write_sequence(dir / "room", options);
  const auto log = dir / "tracker.lcmlog";
  DaemonProcess trackerd(
      fs::path(CVO_TOOLS_DIR) / "cvo-trackerd",
      {"--source", "tum:" + (dir / "room").string(), "--exit-on-eof", "--deterministic", "--lcm-url",
       "file://" + log.string() + "?mode=w", "--set", std::string("trackerd.paced=") + (paced ? "true" : "false"),
       "--set", "trackerd.realtime_priority=0", "--set", "trackerd.lock_memory=false"},
      dir / "tracker.txt");
  EXPECT_EQ(trackerd.wait_for(120s).value_or(-9), 0) << slurp(dir / "tracker.txt");
  return log;
}

// cvo-backendd storing the log's keyframes and local graphs into `store`, the log played at
// `speed` (0: as fast as it can).
std::vector<std::string> backendd_args(const fs::path& log, const fs::path& store, const std::string& speed) {
  return {"--lcm-url",     "file://" + log.string() + "?speed=" + speed,
          "--publish-url", "file://" + (store.parent_path() / "published.lcmlog").string() + "?mode=w",
          "--store",       store.string(),
          "--exit-on-eof"};
}

fs::path backend_store(const fs::path& dir) {
  const auto log = tracker_log(dir);
  fs::create_directories(dir / "state");
  const auto store = dir / "state" / "keyframes.store";
  DaemonProcess backendd(fs::path(CVO_TOOLS_DIR) / "cvo-backendd", backendd_args(log, store, "0"), dir / "backend.txt");
  EXPECT_EQ(backendd.wait_for(300s).value_or(-9), 0) << slurp(dir / "backend.txt");
  return store;
}

// The number after `label` in cvo-map's summary ("records: 17 intact" -> 17), -1 when absent.
long number_after(const std::string& text, const std::string& label) {
  std::smatch m;
  if (!std::regex_search(text, m, std::regex(label + " ?([0-9]+)"))) return -1;
  return std::stol(m[1]);
}

// grid.yaml as map_server reads it, and grid.pgm's size against its header; the cloud's PLY
// header; the octree through OctoMap.
void expect_map_files_load(const fs::path& out) {
  const YAML::Node yaml = YAML::LoadFile((out / "grid.yaml").string());
  for (const char* key :
       {"image", "mode", "resolution", "origin", "negate", "occupied_thresh", "free_thresh", "map_T_grid"})
    EXPECT_TRUE(yaml[key].IsDefined()) << "grid.yaml has no " << key;
  EXPECT_EQ(yaml["image"].as<std::string>(), "grid.pgm");
  EXPECT_EQ(yaml["mode"].as<std::string>(), "trinary");
  EXPECT_EQ(yaml["origin"].size(), 3u);
  EXPECT_EQ(yaml["map_T_grid"].size(), 7u);

  std::ifstream pgm(out / "grid.pgm", std::ios::binary);
  std::string magic;
  long width = 0, height = 0, max = 0;
  pgm >> magic >> width >> height >> max;
  pgm.get();  // the one whitespace byte before the pixels
  EXPECT_EQ(magic, "P5");
  EXPECT_GT(width, 0);
  EXPECT_GT(height, 0);
  EXPECT_EQ(max, 255);
  const std::string pixels{std::istreambuf_iterator<char>(pgm), std::istreambuf_iterator<char>()};
  EXPECT_EQ(static_cast<long>(pixels.size()), width * height) << "grid.pgm's pixels are not its header's size";
  EXPECT_TRUE(std::all_of(pixels.begin(), pixels.end(), [](char c) {
    const auto v = static_cast<unsigned char>(c);
    return v == 0 || v == 205 || v == 254;
  })) << "a trinary grid holds occupied, unknown and free only";

  const std::string ply = bytes_of(out / "cloud.ply").substr(0, 400);
  EXPECT_TRUE(ply.starts_with("ply\n")) << ply;
  EXPECT_GT(number_after(ply, "element vertex"), 0) << ply;

  octomap::OcTree octree(0.1);
  EXPECT_TRUE(octree.readBinary((out / "octomap.bt").string()));
  EXPECT_GT(octree.size(), 0u);
}

TEST(CvoMap, OnAStoreWithADamagedRecordMakesTheMapFromEveryIntactRecord) {
  const test::TempDir dir("cvo_map");
  const auto store = backend_store(dir.path());
  const auto scan = store::read_store(store).scan;
  ASSERT_TRUE(scan.clean());
  std::vector<store::IntactRecord> keyframes;
  for (const auto& r : scan.records)
    if (r.kind == RecordKind::kKeyframe) keyframes.push_back(r);
  ASSERT_GE(keyframes.size(), 4u) << "too few keyframes to damage one in the middle";

  const ToolRun whole = run_tool("cvo-map", quoted(store) + " --out " + quoted(dir.path() / "whole"), dir.path());
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  EXPECT_EQ(number_after(whole.out, "records:"), static_cast<long>(scan.records.size())) << whole.out;
  EXPECT_EQ(number_after(whole.out, "map:"), static_cast<long>(keyframes.size())) << whole.out;

  // One payload byte of the middle keyframe flipped.
  const auto damaged = keyframes[keyframes.size() / 2];
  std::string bytes = bytes_of(store);
  bytes[damaged.at + damaged.bytes / 2] ^= 0x5A;
  std::ofstream(store, std::ios::binary | std::ios::trunc) << bytes;
  const auto files_before = names_in(store.parent_path());

  const auto out = dir.path() / "map";
  const ToolRun r =
      run_tool("cvo-map", quoted(store) + " --out " + quoted(out) + " --plot " + quoted(out / "plot.png"), dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(number_after(r.out, "records:"), static_cast<long>(scan.records.size() - 1)) << r.out;
  EXPECT_EQ(number_after(r.out, "intact,"), 0) << "no intact record is skipped\n" << r.out;
  EXPECT_EQ(number_after(r.out, "map:"), static_cast<long>(keyframes.size() - 1)) << r.out;
  EXPECT_NE(r.out.find("1 of 1 sessions in the map"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("byte " + std::to_string(damaged.at) + ": " + std::to_string(damaged.bytes) + " damaged bytes"),
            std::string::npos)
      << "the damaged record is named by its offset\n"
      << r.err;
  for (const char* file : {"grid.pgm", "grid.yaml", "cloud.ply", "octomap.bt", "plot.png"})
    EXPECT_TRUE(fs::is_regular_file(out / file)) << file;
  expect_map_files_load(out);

  EXPECT_TRUE(bytes_of(store) == bytes) << "cvo-map changed the store";
  EXPECT_EQ(names_in(store.parent_path()), files_before) << "cvo-map made or removed a file beside the store";
}

// While cvo-backendd stores a live tracker's log played at a quarter of its speed (24 s), cvo-map
// is run on its store again and again: until the store holds enough to show which way is up it
// says there is no map yet (and nothing else goes wrong), then it makes the map from what is
// stored so far while the daemon still appends; the daemon's store is whole afterwards.
TEST(CvoMap, ReadsAStoreTheDaemonIsAppendingTo) {
  const test::TempDir dir("cvo_map_live");
  const auto log = tracker_log(dir.path(), true);
  fs::create_directories(dir.path() / "state");
  const auto store = dir.path() / "state" / "keyframes.store";
  DaemonProcess backendd(fs::path(CVO_TOOLS_DIR) / "cvo-backendd", backendd_args(log, store, "0.25"),
                         dir.path() / "backend.txt");
  for (const auto until = std::chrono::steady_clock::now() + 60s;
       !fs::exists(store) && std::chrono::steady_clock::now() < until;)
    std::this_thread::sleep_for(20ms);
  ToolRun r;
  bool appending = false;  // the daemon ran on after the run that made the map
  std::vector<long> records_seen;
  while (backendd.running()) {
    r = run_tool("cvo-map", quoted(store) + " --out " + quoted(dir.path() / "map"), dir.path());
    appending = backendd.running();
    if (r.exit_code == 0) break;
    ASSERT_EQ(r.exit_code, 1) << r.err;
    ASSERT_NE(r.err.find("no map:"), std::string::npos) << r.err;
    records_seen.push_back(number_after(r.err, "no map:"));
  }
  ASSERT_EQ(r.exit_code, 0) << "no run made a map while the daemon appended\n" << r.err;
  EXPECT_TRUE(appending) << "the daemon ended while cvo-map ran: the test did not read a store being appended to";
  EXPECT_GE(number_after(r.out, "records:"), 2) << r.out;
  EXPECT_GE(number_after(r.out, "map:"), 1) << r.out;
  expect_map_files_load(dir.path() / "map");
  EXPECT_TRUE(std::is_sorted(records_seen.begin(), records_seen.end())) << "the store grew between the runs";

  ASSERT_EQ(backendd.wait_for(120s).value_or(-9), 0) << slurp(dir.path() / "backend.txt");
  const auto after = store::read_store(store).scan;
  EXPECT_TRUE(after.clean()) << describe_damage(store, after, "", "");
  EXPECT_GT(static_cast<long>(after.records.size()), number_after(r.out, "records:")) << "the daemon went on appending";
}

TEST(CvoMap, AMissingStoreOrAForeignFileIsBadInputThatNamesIt) {
  const test::TempDir dir("cvo_map_bad");
  const auto missing = dir.path() / "no.store";
  const ToolRun none = run_tool("cvo-map", quoted(missing) + " --out " + quoted(dir.path() / "m"), dir.path());
  EXPECT_EQ(none.exit_code, 1) << none.err;
  EXPECT_NE(none.err.find(missing.string()), std::string::npos) << none.err;

  const auto foreign = dir.write("foreign.store", "P5\n2 2\n255\n....");
  const ToolRun other = run_tool("cvo-map", quoted(foreign) + " --out " + quoted(dir.path() / "m"), dir.path());
  EXPECT_EQ(other.exit_code, 1) << other.err;
  EXPECT_NE(other.err.find(foreign.string()), std::string::npos) << other.err;
  EXPECT_NE(other.err.find("not a cvo-backendd keyframe store"), std::string::npos) << other.err;
  EXPECT_EQ(bytes_of(foreign), "P5\n2 2\n255\n....");

  // A store with no record: nothing to map, said so.
  const auto empty = dir.write("empty.store", "CVOKFS1\n");
  const ToolRun nothing = run_tool("cvo-map", quoted(empty) + " --out " + quoted(dir.path() / "m"), dir.path());
  EXPECT_EQ(nothing.exit_code, 1) << nothing.err;
  EXPECT_NE(nothing.err.find("no map: 0 intact records"), std::string::npos) << nothing.err;
  EXPECT_FALSE(fs::exists(dir.path() / "m" / "grid.yaml"));
}

TEST(CvoMap, FollowsTheCommandLineContract) {
  const test::TempDir dir("cvo_map_cli");
  testing::expect_cli_contract("cvo-map", "", {"STORE", "--out", "--plot", "--config", "--set", "--vocabulary"},
                               dir.path());
  const auto store = dir.write("s.store", "CVOKFS1\n");
  const ToolRun no_out = run_tool("cvo-map", quoted(store), dir.path());
  EXPECT_EQ(no_out.exit_code, 2) << no_out.err;
  EXPECT_NE(no_out.err.find("--out"), std::string::npos) << no_out.err;
  testing::expect_set_needs_key_equals_value("cvo-map", quoted(store) + " --out " + quoted(dir.path() / "m"),
                                             dir.path());
  const ToolRun bad_key = run_tool(
      "cvo-map", quoted(store) + " --out " + quoted(dir.path() / "m") + " --set mapping.no_such=1", dir.path());
  EXPECT_EQ(bad_key.exit_code, 2) << bad_key.err;
  EXPECT_NE(bad_key.err.find("mapping.no_such"), std::string::npos) << bad_key.err;
}

}  // namespace
}  // namespace cvo
