// libusb and the cameras: the committed id table, the permission and speed diagnoses on
// constructed cases (plain data: descriptor fields, speed, node mode/owner/group, the user's
// groups), the hot-plug handler re-opening a ReconnectingSource at once, and enumeration and
// cvo-cameras for real (no camera here: an empty list, exit 0, valid JSON).
#include <sys/stat.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>

#include "drivers/frame_source.hpp"
#include "drivers/open_source.hpp"
#include "drivers/reconnecting_source.hpp"
#include "drivers/usb_cameras.hpp"
#include "libcvo/io/input_error.hpp"
#include "support/cli_contract.hpp"
#include "support/run_tool.hpp"
#include "support/temp_dir.hpp"

namespace cvo::drivers {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// ---- the table ------------------------------------------------------------------------------

TEST(CameraTable, CommittedTableParsesAndEveryIdNamesItsSource) {
  const auto table = CameraTable::load();
  ASSERT_GE(table.cameras().size(), 8u);
  for (const auto& c : table.cameras()) {
    EXPECT_TRUE(c.source.starts_with("https://")) << to_string(c.ids) << ": " << c.source;
    EXPECT_TRUE(c.scheme == "openni2" || c.scheme == "v4l2") << to_string(c.ids);
    EXPECT_FALSE(c.name.empty());
  }
  const auto* d435 = table.find({0x8086, 0x0b07});
  ASSERT_NE(d435, nullptr);
  EXPECT_EQ(d435->needs, UsbSpeed::kSuper);
  EXPECT_EQ(d435->scheme, "v4l2");
  ASSERT_NE(table.find({0x1d27, 0x0601}), nullptr);
  EXPECT_EQ(table.find({0x1d27, 0x0601})->scheme, "openni2");
  ASSERT_NE(table.find({0x045e, 0x02ae}), nullptr);
  EXPECT_EQ(table.find({0x1234, 0x5678}), nullptr);
  EXPECT_EQ(table.ids_for_spec("v4l2:/dev/video0,/dev/video2").size(), 4u);
  EXPECT_TRUE(table.ids_for_spec("tum:/data").empty());
}

const std::string kHeader = "# comment\nvendor\tproduct\tname\tscheme\tspeed\tspec\tsource\n";

std::string parse_error(const std::string& text) {
  try {
    CameraTable::parse(text, "t.tsv");
  } catch (const io::InputError& e) {
    return e.what();
  }
  return "<parsed>";
}

TEST(CameraTable, BadLinesAreRefusedWithFileAndLine) {
  EXPECT_EQ(
      CameraTable::parse(kHeader + "8086\t0b07\tD435\tv4l2\tsuper\tv4l2:X\thttps://a\n", "t.tsv").cameras().size(), 1u);
  EXPECT_TRUE(contains(parse_error(kHeader + "8086\t0b07\tD435\tv4l2\tsuper\tv4l2:X\t\n"),
                       "t.tsv:3: every id needs its source"));
  EXPECT_TRUE(contains(parse_error(kHeader + "8086\t0b07\tD435\tv4l2\tsuper\tv4l2:X\n"), "t.tsv:3: expected 7"));
  EXPECT_TRUE(contains(parse_error(kHeader + "808g\t0b07\tD\tv4l2\tsuper\tv4l2:X\ts\n"), "4 hex digits"));
  EXPECT_TRUE(contains(parse_error(kHeader + "8086\t0b07\tD\tuvc\tsuper\tv4l2:X\ts\n"), "scheme"));
  EXPECT_TRUE(contains(parse_error(kHeader + "8086\t0b07\tD\tv4l2\tfast\tv4l2:X\ts\n"), "speed"));
  EXPECT_TRUE(
      contains(parse_error(kHeader + "8086\t0b07\tD\tv4l2\tsuper\topenni2:any\ts\n"), "spec must use the scheme"));
  EXPECT_TRUE(
      contains(parse_error(kHeader + "8086\t0b07\tD\tv4l2\tsuper\tv4l2:X\ts\n8086\t0b07\tD\tv4l2\tsuper\tv4l2:X\ts\n"),
               "t.tsv:4: 8086:0b07 is listed twice"));
  EXPECT_TRUE(contains(parse_error("8086\t0b07\tD\tv4l2\tsuper\tv4l2:X\ts\n"), "t.tsv:1: expected the header"));
  EXPECT_TRUE(contains(parse_error("# nothing\n"), "no header line"));
}

// ---- diagnoses on constructed cases ----------------------------------------------------------

NodeAccess usb_node(unsigned mode, uid_t uid, gid_t gid, const std::string& owner, const std::string& group) {
  return {"/dev/bus/usb/002/005", true, mode, uid, gid, owner, group};
}

const UserIds kAlice{1000, {1000, 44}, "alice"};  // in group video (44), not in plugdev (46)

FoundCamera camera(UsbIds ids, UsbSpeed speed, NodeAccess node) {
  FoundCamera c;
  c.known =
      ids.vendor == 0x8086
          ? KnownCamera{ids, "Intel RealSense D435", "v4l2", UsbSpeed::kSuper, "v4l2:COLOUR,DEPTH", "s"}
          : KnownCamera{
                ids, "PrimeSense PS1080", "openni2", UsbSpeed::kHigh, "openni2:{vendor}/{product}@{bus}/{address}",
                "s"};
  c.bus = 2;
  c.address = 5;
  c.ports = {1, 4};
  c.speed = speed;
  c.serial = "A1";
  c.node = std::move(node);
  return c;
}

TEST(UsbDiagnosis, WhoMayOpenANode) {
  EXPECT_TRUE(may_open(usb_node(0660, 1000, 46, "alice", "plugdev"), kAlice)) << "owner with rw";
  EXPECT_FALSE(may_open(usb_node(0460, 1000, 44, "alice", "video"), kAlice)) << "owner bits decide for the owner";
  EXPECT_TRUE(may_open(usb_node(0660, 0, 44, "root", "video"), kAlice)) << "member of a group with rw";
  EXPECT_FALSE(may_open(usb_node(0664, 0, 46, "root", "plugdev"), kAlice)) << "not a member, others read only";
  EXPECT_TRUE(may_open(usb_node(0666, 0, 0, "root", "root"), kAlice)) << "others rw";
  EXPECT_TRUE(may_open(usb_node(0600, 5, 5, "x", "x"), UserIds{0, {0}, "root"})) << "root";
  NodeAccess missing = usb_node(0666, 0, 0, "root", "root");
  missing.exists = false;
  EXPECT_FALSE(may_open(missing, kAlice));
}

TEST(UsbDiagnosis, GroupWithAccessNamesTheGroupToJoin) {
  const auto why =
      diagnose(camera({0x1d27, 0x0601}, UsbSpeed::kHigh, usb_node(0664, 0, 46, "root", "plugdev")), kAlice);
  EXPECT_TRUE(contains(why, "/dev/bus/usb/002/005 is crw-rw-r-- root:plugdev")) << why;
  EXPECT_TRUE(contains(why, "sudo usermod -aG plugdev alice")) << why;
  EXPECT_FALSE(contains(why, "udev")) << why;
}

TEST(UsbDiagnosis, NodeWithoutGroupAccessNamesTheUdevRule) {
  const auto why = diagnose(camera({0x1d27, 0x0601}, UsbSpeed::kHigh, usb_node(0664, 0, 0, "root", "root")), kAlice);
  EXPECT_TRUE(contains(why, "root:root")) << why;
  EXPECT_TRUE(contains(why,
                       "SUBSYSTEM==\"usb\", ATTR{idVendor}==\"1d27\", ATTR{idProduct}==\"0601\", MODE=\"0660\", "
                       "GROUP=\"plugdev\""))
      << why;
  EXPECT_TRUE(contains(why, "usermod -aG plugdev alice")) << why;
}

TEST(UsbDiagnosis, SlowerPortThanTheCameraNeeds) {
  const auto open_node = usb_node(0666, 0, 0, "root", "root");
  const auto why = diagnose(camera({0x8086, 0x0b07}, UsbSpeed::kHigh, open_node), kAlice);
  EXPECT_TRUE(contains(why, "connected at high (480 Mbit/s, USB 2) but needs super (5 Gbit/s, USB 3)")) << why;
  EXPECT_EQ(diagnose(camera({0x8086, 0x0b07}, UsbSpeed::kSuper, open_node), kAlice), "");
  EXPECT_EQ(diagnose(camera({0x8086, 0x0b07}, UsbSpeed::kUnknown, open_node), kAlice), "") << "no speed: no claim";
  EXPECT_EQ(diagnose(camera({0x1d27, 0x0601}, UsbSpeed::kHigh, open_node), kAlice), "") << "a USB 2 camera";
  EXPECT_TRUE(contains(diagnose(camera({0x1d27, 0x0601}, UsbSpeed::kFull, open_node), kAlice), "needs high"));
  // Both at once: both said.
  const auto both =
      diagnose(camera({0x8086, 0x0b07}, UsbSpeed::kHigh, usb_node(0664, 0, 46, "root", "plugdev")), kAlice);
  EXPECT_TRUE(contains(both, "plugdev") && contains(both, "needs super")) << both;
}

TEST(UsbDiagnosis, OpenFailureExplanations) {
  const auto open_node = usb_node(0666, 0, 0, "root", "root");
  EXPECT_EQ(explain_open_failure("openni2:any", {}, {}, kAlice),
            "libusb: no openni2 camera of the known ids on the USB bus (cvo-cameras lists the cameras it sees)");
  // A RealSense on the bus does not make an openni2 camera.
  const std::vector<FoundCamera> d435{camera({0x8086, 0x0b07}, UsbSpeed::kHigh, open_node)};
  EXPECT_TRUE(contains(explain_open_failure("openni2:any", d435, {}, kAlice), "no openni2 camera"));
  const auto slow = explain_open_failure("v4l2:/dev/video0,/dev/video2", d435, {}, kAlice);
  EXPECT_TRUE(contains(slow,
                       "8086:0b07 Intel RealSense D435, serial A1, high (480 Mbit/s, USB 2) on 2-1.4: it is "
                       "connected at high"))
      << slow;
  const std::vector<FoundCamera> ok{camera({0x1d27, 0x0601}, UsbSpeed::kHigh, open_node)};
  EXPECT_TRUE(contains(explain_open_failure("openni2:any", ok, {}, kAlice), "libusb sees no problem with it"));

  NodeAccess missing{"/dev/video9", false, 0, 0, 0, "", ""};
  NodeAccess video{"/dev/video0", true, 0660, 0, 45, "root", "render"};
  const auto nodes = explain_open_failure("v4l2:/dev/video9,/dev/video0", {}, {missing, video}, kAlice);
  EXPECT_TRUE(contains(nodes, "/dev/video9 does not exist")) << nodes;
  EXPECT_TRUE(contains(nodes, "/dev/video0 is crw-rw---- root:render")) << nodes;
  EXPECT_TRUE(contains(nodes, "usermod -aG render alice")) << nodes;
  EXPECT_TRUE(contains(nodes, "no v4l2 camera")) << nodes;
}

TEST(UsbCameras, SpecPortAndIdentity) {
  const auto ps = camera({0x1d27, 0x0601}, UsbSpeed::kHigh, usb_node(0666, 0, 0, "root", "root"));
  EXPECT_EQ(source_spec(ps), "openni2:1d27/0601@2/5");
  EXPECT_EQ(port_text(ps), "2-1.4");
  EXPECT_EQ(identity(ps), "1d27:0601 PrimeSense PS1080, serial A1, high (480 Mbit/s, USB 2) on 2-1.4");
  EXPECT_EQ(parse_usb_speed("super+"), UsbSpeed::kSuperPlus);
  EXPECT_FALSE(parse_usb_speed("unknown").has_value());
}

// ---- hot-plug ---------------------------------------------------------------------------------

TEST(UsbHotplug, FilterPassesOnlyArrivalsOfItsIds) {
  int calls = 0;
  const UsbArrivalFilter filter({{0x8086, 0x0b07}, {0x1d27, 0x0601}}, [&] { ++calls; });
  EXPECT_TRUE(filter.on_event({true, {0x8086, 0x0b07}}));
  EXPECT_FALSE(filter.on_event({false, {0x8086, 0x0b07}})) << "leaving";
  EXPECT_FALSE(filter.on_event({true, {0x046d, 0x0825}})) << "another device";
  EXPECT_TRUE(filter.on_event({true, {0x1d27, 0x0601}}));
  EXPECT_EQ(calls, 2);
}

// A camera that opens once it has been plugged in.
class OneFrameSource final : public FrameSource {
 public:
  ReadResult read(core::RgbdFrame& frame, milliseconds) override {
    frame.index = 0;
    return {ReadStatus::kFrame, core::BadKind::kContent, {}};
  }
  [[nodiscard]] std::string describe() const override { return "plugged"; }
};

TEST(UsbHotplug, ArrivalReopensAtOnceInsteadOfWaitingOutTheBackoff) {
  std::atomic<bool> plugged{false};
  ReconnectingSource source(
      "camera",
      [&]() -> std::unique_ptr<FrameSource> {
        if (!plugged) throw SourceError("camera", "no device");
        return std::make_unique<OneFrameSource>();
      },
      Backoff{std::chrono::seconds(30), std::chrono::seconds(30), 2.0});  // polling alone: 30 s
  const UsbArrivalFilter handler({{0x8086, 0x0b07}}, [&] { source.device_arrived(); });

  core::RgbdFrame frame;
  ASSERT_EQ(source.read(frame, milliseconds(50)).status, ReadStatus::kDisconnected);
  EXPECT_EQ(source.read(frame, milliseconds(50)).status, ReadStatus::kTimeout) << "back-off not due";
  EXPECT_FALSE(handler.on_event({true, {0x046d, 0x0825}}));  // someone else's device: no attempt
  EXPECT_EQ(source.read(frame, milliseconds(50)).status, ReadStatus::kTimeout);
  EXPECT_EQ(source.open_attempts(), 1u);

  // Plugged in while a read waits: it wakes, opens and returns the frame well before its timeout.
  std::thread libusb_thread([&] {
    std::this_thread::sleep_for(milliseconds(100));
    plugged = true;
    handler.on_event({true, {0x8086, 0x0b07}});
  });
  const auto start = Clock::now();
  const auto r = source.read(frame, milliseconds(5000));
  const double waited = std::chrono::duration<double>(Clock::now() - start).count();
  libusb_thread.join();
  EXPECT_EQ(r.status, ReadStatus::kFrame) << r.message;
  EXPECT_LT(waited, 2.0);
  EXPECT_EQ(source.open_attempts(), 2u);
  EXPECT_EQ(source.arrivals(), 1u);
  EXPECT_EQ(source.gap_count(), 1u);
  EXPECT_TRUE(source.gaps().back().end.has_value());
}

TEST(UsbHotplug, ArrivalRestartsTheBackoffFromItsInitialWait) {
  int opens = 0;
  ReconnectingSource source(
      "camera",
      [&]() -> std::unique_ptr<FrameSource> {
        ++opens;
        if (opens < 3) throw SourceError("camera", "not ready yet");
        return std::make_unique<OneFrameSource>();
      },
      Backoff{milliseconds(20), milliseconds(60000), 1000.0});  // 20 ms, then 20 s
  core::RgbdFrame frame;
  ASSERT_EQ(source.read(frame, milliseconds(10)).status, ReadStatus::kDisconnected);  // next wait: 20 s
  source.device_arrived();
  EXPECT_EQ(source.read(frame, milliseconds(10)).status, ReadStatus::kTimeout) << "tried at once, still not ready";
  EXPECT_EQ(opens, 2);
  ReadResult r;
  const auto start = Clock::now();
  while ((r = source.read(frame, milliseconds(50))).status == ReadStatus::kTimeout &&
         Clock::now() - start < std::chrono::seconds(3)) {
  }
  EXPECT_EQ(r.status, ReadStatus::kFrame) << "retried after the initial 20 ms, not 20 s";
}

TEST(UsbHotplug, SpecSourcesWatchTheirCamerasIds) {
  // libusb on Linux has hot-plug; a device spec watches, a folder does not.
  ReconnectingSource camera("openni2:any", SourceOptions{});
  ReconnectingSource folder("tum:/no/such/folder", SourceOptions{});
  EXPECT_FALSE(folder.watching_hotplug());
  if (!camera.watching_hotplug()) GTEST_SKIP() << "libusb reports no hot-plug here: back-off only";
  SUCCEED();
}

// ---- for real ---------------------------------------------------------------------------------

TEST(UsbCameras, EnumerationRunsAndFindsOnlyKnownIds) {
  const auto table = CameraTable::load();
  const auto found = enumerate_cameras(table);
  for (const auto& c : found) EXPECT_NE(table.find(c.known.ids), nullptr);
  if (found.empty()) {
    EXPECT_TRUE(contains(usb_open_hint("openni2:any"), "no openni2 camera"));
  }
}

TEST(UsbCameras, FailedOpensCarryWhatLibusbKnows) {
  try {
    open_source("openni2:any");
    GTEST_SKIP() << "an OpenNI2 camera is attached and opened, so there is no failed open to inspect";
  } catch (const SourceError& e) {
    EXPECT_TRUE(contains(e.what(), "libusb")) << e.what();
  }
  SourceOptions options;
  options.intrinsics = core::Intrinsics{};
  options.intrinsics->width = 640;
  options.intrinsics->height = 480;
  options.intrinsics->fx = options.intrinsics->fy = 525;
  options.intrinsics->cx = 320;
  options.intrinsics->cy = 240;
  try {
    open_source("v4l2:/dev/cvo-no-such-video,/dev/cvo-no-such-depth", options);
    FAIL() << "opened";
  } catch (const SourceError& e) {
    EXPECT_TRUE(contains(e.what(), "no such device node")) << e.what();
    EXPECT_TRUE(contains(e.what(), "libusb: /dev/cvo-no-such-video does not exist")) << e.what();
  }
  EXPECT_EQ(usb_open_hint("tum:/x"), "");
}

TEST(CvoCameras, NoCameraIsAnEmptyListExitZeroAndValidJson) {
  test::TempDir dir;
  const auto json = testing::run_tool("cvo-cameras", "--json", dir.path());
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_EQ(testing::json_value(json.out, "known_ids"), std::to_string(CameraTable::load().cameras().size()));
  std::ofstream(dir.path() / "out.json") << json.out;
  const std::string check =
      "python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); "
      "assert isinstance(d[\"cameras\"], list)' " +
      testing::quoted(dir.path() / "out.json");
  EXPECT_EQ(std::system(check.c_str()), 0) << json.out;
  if (testing::json_value(json.out, "cameras") == "[]") {
    const auto text = testing::run_tool("cvo-cameras", "", dir.path());
    EXPECT_EQ(text.exit_code, 0);
    EXPECT_TRUE(contains(text.out, "no RGB-D camera on the USB bus")) << text.out;
  }
  EXPECT_EQ(testing::run_tool("cvo-cameras", "--frob", dir.path()).exit_code, 2);
  EXPECT_EQ(testing::run_tool("cvo-cameras", "--table /no/such.tsv", dir.path()).exit_code, 1);
}

TEST(CvoCameras, HelpListsEveryOptionAndAnUnknownOneExitsTwoNamingIt) {
  test::TempDir dir;
  testing::expect_cli_contract("cvo-cameras", "", {"--json", "--table"}, dir.path());
}

// --table names the table the report is about; an argument that is no option is a usage error.
TEST(CvoCameras, TheTableGivenIsTheOneReported) {
  test::TempDir dir;
  const auto table = default_camera_table_file();
  const auto json = testing::run_tool("cvo-cameras", "--json --table " + testing::quoted(table), dir.path());
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_EQ(testing::json_value(json.out, "table"), nlohmann::ordered_json(table.string()).dump()) << json.out;
  EXPECT_EQ(testing::json_value(json.out, "known_ids"), std::to_string(CameraTable::load(table).cameras().size()));
  EXPECT_EQ(testing::run_tool("cvo-cameras", "extra", dir.path()).exit_code, 2);
  EXPECT_EQ(testing::run_tool("cvo-cameras", "--table", dir.path()).exit_code, 2) << "--table needs a file";
}

}  // namespace
}  // namespace cvo::drivers
