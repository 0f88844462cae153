// What an .oni file is, read before OpenNI sees it (drivers/oni_file.hpp), on files built byte by
// byte as OpenNI2's Recorder lays them out; and the camera facts that stand in for a field of view
// (zero_plane.hpp, factory_intrinsics.hpp). Played through OpenNI: openni2_virtual/oni_recordings_test.
#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "drivers/factory_intrinsics.hpp"
#include "drivers/oni_file.hpp"
#include "drivers/zero_plane.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::drivers {
namespace {

namespace fs = std::filesystem;

void put(std::vector<char>& out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<char>(v >> (8 * i)));
}

// A recording of format 1.0.1.0: header, then records of (type, node, payload bytes), closed or not.
std::vector<char> recording(const std::vector<std::array<std::uint32_t, 3>>& records, std::uint32_t max_node) {
  std::vector<char> out{'N', 'I', '1', '0', 1, 0, 1, 0};
  put(out, 0, 4);         // build
  put(out, ~0ull, 8);     // max timestamp
  put(out, max_node, 4);  // patched at close
  for (const auto& [type, node, payload] : records) {
    put(out, 0x0052494E, 4);
    put(out, type, 4);
    put(out, node, 4);
    put(out, 28, 4);  // fields: the header alone
    put(out, payload, 4);
    put(out, 0, 8);
    out.insert(out.end(), payload, 'x');
  }
  return out;
}

fs::path write(const fs::path& dir, const std::string& name, const std::vector<char>& bytes) {
  const auto path = dir / name;
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

constexpr std::uint32_t kNewData = 0x0A, kEnd = 0x0B;

TEST(OniFile, SaysWhatIsWrongWithAFile) {
  cvo::test::TempDir dir;
  EXPECT_EQ(inspect_oni(dir.path() / "missing.oni").problem, "no such file");
  EXPECT_EQ(inspect_oni(dir.path()).problem, "not a regular file");
  const auto text = write(dir.path(), "text.oni", {'h', 'e', 'l', 'l', 'o'});
  EXPECT_NE(inspect_oni(text).problem.find("not an ONI recording (it starts with 68 65 6c 6c"), std::string::npos);
  auto closed = recording({{kNewData, 1, 10}, {kEnd, 0, 0}}, 1);
  const auto stub = write(dir.path(), "stub.oni", {closed.begin(), closed.begin() + 10});
  EXPECT_NE(inspect_oni(stub).problem.find("truncated: 10 bytes"), std::string::npos) << inspect_oni(stub).problem;
  auto future = closed;
  future[5] = 9;  // version 1.9.1.0
  EXPECT_NE(inspect_oni(write(dir.path(), "future.oni", future)).problem.find("cannot play"), std::string::npos);
  const auto empty = write(dir.path(), "empty.oni", recording({{kEnd, 0, 0}}, 0));
  EXPECT_NE(inspect_oni(empty).problem.find("holds no frame"), std::string::npos);
}

TEST(OniFile, TellsAClosedRecordingFromOneNeverClosedOrCutOff) {
  cvo::test::TempDir dir;
  const auto closed =
      inspect_oni(write(dir.path(), "closed.oni", recording({{kNewData, 1, 10}, {kNewData, 2, 7}, {kEnd, 0, 0}}, 2)));
  EXPECT_TRUE(closed.problem.empty()) << closed.problem;
  EXPECT_TRUE(closed.closed);
  EXPECT_FALSE(closed.needs_repair());
  EXPECT_EQ(closed.data_records, 2u);

  // Killed: no END record, the header's node count as it was when the recorder started.
  const auto killed_bytes = recording({{kNewData, 1, 10}, {kNewData, 2, 7}}, 0);
  const auto killed_file = write(dir.path(), "killed.oni", killed_bytes);
  const auto killed = inspect_oni(killed_file);
  EXPECT_TRUE(killed.needs_repair());
  EXPECT_FALSE(killed.truncated);
  EXPECT_EQ(killed.max_node_id, 2u);
  EXPECT_EQ(killed.usable_bytes, killed_bytes.size());

  // Cut inside the second record: the first is whole.
  const auto cut = inspect_oni(write(dir.path(), "cut.oni", {killed_bytes.begin(), killed_bytes.end() - 3}));
  EXPECT_TRUE(cut.truncated);
  EXPECT_EQ(cut.data_records, 1u);
  EXPECT_EQ(cut.usable_bytes, 24u + 28u + 10u);

  // The repaired copy is what closing would have written: closed, the same frames.
  repair_oni_copy(killed_file, killed, dir.path() / "repaired.oni");
  const auto repaired = inspect_oni(dir.path() / "repaired.oni");
  EXPECT_TRUE(repaired.closed) << repaired.summary();
  EXPECT_EQ(repaired.data_records, 2u);
}

TEST(OniFile, AFileUriIsNoDevice) {
  EXPECT_TRUE(is_oni_path("/data/kinect.ONI"));
  EXPECT_TRUE(is_oni_path("missing.oni"));
  EXPECT_FALSE(is_oni_path("any"));
  EXPECT_FALSE(is_oni_path("1d27/0601@1/5"));
}

TEST(CameraFacts, ZeroPlaneAndPublishedFocalLengthsOfAKinect) {
  // PS1080's field of view from ZPD and ZPPS, 2 atan(ZPPS 1280 / 2 / ZPD), as a focal length.
  EXPECT_NEAR(zero_plane_focal_px(120, 0.1042, 640), 575.8157, 1e-3);
  EXPECT_NEAR(zero_plane_focal_px(120, 0.1042, 320), 575.8157 / 2, 1e-3);
  EXPECT_EQ(zero_plane_focal_px(0, 0.1042, 640), 0.0);
  const auto kinect = factory_camera(0x045e, 0x02ae, "");
  ASSERT_TRUE(kinect.has_value());
  EXPECT_NEAR(kinect->focal_px_at_640, zero_plane_focal_px(120, 0.1042, 640), 0.01 * kinect->focal_px_at_640);
  EXPECT_FALSE(kinect->source.empty());
  EXPECT_TRUE(factory_camera(0, 0, "ASUS Xtion PRO LIVE").has_value());
  EXPECT_TRUE(factory_camera(0x2bc5, 0x0401, "").has_value());
  EXPECT_FALSE(factory_camera(0, 0, "virtual TUM device").has_value());
  EXPECT_FALSE(factory_camera(0, 0, "oni File").has_value());
}

}  // namespace
}  // namespace cvo::drivers
