// The real v4l2: driver (drivers/v4l2_source.cpp, v4l2_formats.cpp) against emulated uvcvideo
// cameras (tests/support/v4l2_emulator, loaded with LD_PRELOAD; the cameras are described in this
// folder's CMakeLists.txt): format negotiation, mmap buffers, frames paired by capture time,
// lost buffers counted, unplug and reconnection. And the emulator's answers to raw ioctls, as
// uvcvideo gives them.
#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "drivers/frame_source.hpp"
#include "drivers/open_source.hpp"
#include "drivers/reconnecting_source.hpp"
#include "tests/drivers/v4l2_emulator/emulated.hpp"
#include "tests/support/slowdown.hpp"

namespace cvo::drivers {
namespace {

using namespace std::chrono_literals;
using cvo::testing::ClipImages;
using cvo::testing::emulator_stats;

// The cameras every test of this executable has (each test is a process of its own under ctest,
// so one camera's unplug touches no other test). Depth nodes are at the colour size where frames
// are streamed: v4l2: takes depth only at the colour size (the D435's 848x480 is refused).
constexpr const char* kCameras[][2] = {
    {"CVO_V4L2_EMULATOR", "colour=/dev/video90,depth=/dev/video91,depth_size=640x480,depth_fps=15"},
    {"CVO_V4L2_EMULATOR_2", "colour=/dev/video92,depth=/dev/video93,depth_size=640x480,colour_format=mjpeg"},
    {"CVO_V4L2_EMULATOR_3", "colour=/dev/video94,depth=/dev/video95"},
    {"CVO_V4L2_EMULATOR_4",
     "colour=/dev/video96,depth=/dev/video97,depth_size=640x480,unplug_after=20,replug_after_s=0.3"},
    {"CVO_V4L2_EMULATOR_5", "colour=/dev/video98,depth=/dev/video99,depth_size=640x480"},
    {"CVO_V4L2_EMULATOR_6",
     "colour=/dev/video100,depth=/dev/video101,depth_size=640x480,unplug_after=5,replug_after_s=-1"},
    {"CVO_V4L2_EMULATOR_7", "colour=/dev/video102,depth=/dev/video103,depth_size=640x480,error_every=3"},
};

// Before any test: this executable again, with the emulator in LD_PRELOAD and the cameras above
// playing the clip (CVO_V4L2_EMULATOR_TEST marks the second run).
__attribute__((constructor)) void run_again_with_the_emulator(int, char** argv) {
  if (std::getenv("CVO_V4L2_EMULATOR_TEST") != nullptr) return;
  for (const auto& [name, camera] : kCameras)
    ::setenv(name, (std::string(camera) + ",tum=" CVO_TEST_DATA_DIR "/fr1_rpy_50").c_str(), 1);
  ::setenv("CVO_V4L2_EMULATOR_TEST", "1", 1);
  ::setenv("LD_PRELOAD", CVO_V4L2_EMULATOR_PRELOAD, 1);
  ::execv("/proc/self/exe", argv);
  std::perror("v4l2_emulator_test: running again with the V4L2 emulator");  // the tests then say it is missing
}

const std::string kHalfRateDepth = "/dev/video90,/dev/video91";  // YUYV 30 Hz, Z16 640x480 15 Hz
const std::string kMjpeg = "/dev/video92,/dev/video93";          // MJPEG 30 Hz, Z16 640x480 30 Hz
const std::string kD435 = "/dev/video94,/dev/video95";           // the defaults: Z16 848x480
const std::string kReplugs = "/dev/video96,/dev/video97";        // unplugged after 20 frames, back 0.3 s later
const std::string kPlain = "/dev/video98,/dev/video99";          // YUYV and Z16 640x480 at 30 Hz
const std::string kCorrupt = "/dev/video102,/dev/video103";      // every third colour frame flagged ERROR
const std::string kLeaves = "/dev/video100";                     // colour of a camera unplugged for good after 5 frames

std::string node(const std::string& pair, int k) {
  return k == 0 ? pair.substr(0, pair.find(',')) : pair.substr(pair.find(',') + 1);
}

SourceOptions fr1_in_mm() {
  SourceOptions o;
  o.intrinsics = core::camera_preset("tum_fr1");
  o.intrinsics->depth_scale = 1000;  // the emulated cameras' Z16 unit, a RealSense's
  o.fps = 30;
  return o;
}

// Reads until a frame (a bounded number of tries, never a timed assertion).
ReadResult read_frame(FrameSource& source, core::RgbdFrame& frame) {
  ReadResult r;
  for (int i = 0; i < 100; ++i) {
    r = source.read(frame, cvo::testing::scaled(200ms));
    if (r.status != ReadStatus::kTimeout) return r;
  }
  return r;
}

// Which clip entry each read frame shows: colour and depth must show the same one.
void expect_frames_of_one_entry(FrameSource& source, const ClipImages& clip, int frames,
                                std::vector<std::size_t>& entries) {
  core::RgbdFrame frame;
  for (int i = 0; i < frames; ++i) {
    const auto r = read_frame(source, frame);
    ASSERT_EQ(r.status, ReadStatus::kFrame) << r.message;
    const auto [depth_entry, depth_distance] = ClipImages::closest(clip.depth_mm, frame.depth);
    const auto [colour_entry, colour_distance] = ClipImages::closest(clip.bgr, frame.bgr);
    EXPECT_EQ(depth_distance, 0) << "depth arrives exactly, in millimetres";
    EXPECT_EQ(colour_entry, depth_entry) << "frame " << i << ": colour and depth of different moments";
    EXPECT_LT(colour_distance, 4) << "frame " << i << ": only the colour encoding's loss";
    EXPECT_LE(std::abs(frame.timestamp - frame.depth_timestamp), 0.5 / 30 + 1e-3) << "frame " << i;
    EXPECT_EQ(frame.bgr.size(), cv::Size(640, 480));
    if (!entries.empty()) {
      EXPECT_GT(depth_entry, entries.back()) << "frame " << i << " goes back in time";
    }
    entries.push_back(depth_entry);
  }
}

TEST(EmulatedV4l2, YuyvAndHalfRateZ16PairByCaptureTime) {
  const ClipImages clip;
  auto source = open_source("v4l2:" + kHalfRateDepth, fr1_in_mm());
  EXPECT_NE(source->describe().find("colour YUYV"), std::string::npos) << source->describe();
  std::vector<std::size_t> entries;
  expect_frames_of_one_entry(*source, clip, 8, entries);
  // Depth comes at 15 Hz: every other colour frame has no partner and is counted.
  EXPECT_GE(source->lost_frames(), entries.size() - 1);
  for (const auto entry : entries) EXPECT_EQ(entry % 2, 0u) << "depth frame k shows entry 2k";
}

TEST(EmulatedV4l2, MjpegColourPairsFrameForFrame) {
  const ClipImages clip;
  auto source = open_source("v4l2:" + kMjpeg, fr1_in_mm());
  EXPECT_NE(source->describe().find("colour MJPG"), std::string::npos) << source->describe();
  std::vector<std::size_t> entries;
  expect_frames_of_one_entry(*source, clip, 8, entries);
}

TEST(EmulatedV4l2, DepthAtAnotherSizeThanColourIsRefused) {
  // A D435's depth node streams 848x480 only: v4l2: wants both nodes at the intrinsics' size
  // (depth registered to colour), so it says so instead of streaming.
  try {
    open_source("v4l2:" + kD435, fr1_in_mm());
    ADD_FAILURE() << "opened";
  } catch (const SourceError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(node(kD435, 1)), std::string::npos) << what;
    EXPECT_NE(what.find("does not stream Z16  at 640x480"), std::string::npos) << what;
  }
}

// With the camera file's depth sensor (here: the same lens, the emulator's 848x480 depth being
// the clip's depth stretched to that size), the 848x480 depth is registered to 640x480 colour
// before the frame leaves the driver, and it is the clip's depth again.
TEST(EmulatedV4l2, ASeparateDepthSensorIsRegisteredToColour) {
  SourceOptions options = fr1_in_mm();
  core::Intrinsics sensor = *options.intrinsics;
  const double sx = 848.0 / 640.0;
  sensor.fx *= sx;
  sensor.cx = (sensor.cx + 0.5) * sx - 0.5;
  sensor.width = 848;
  options.depth_sensor = core::DepthSensor{sensor, core::SE3()};
  auto source = open_source("v4l2:" + kD435, options);
  EXPECT_NE(source->describe().find("depth 848x480 registered to colour"), std::string::npos) << source->describe();
  const ClipImages clip;
  core::RgbdFrame frame;
  for (int i = 0; i < 5; ++i) {
    ASSERT_EQ(read_frame(*source, frame).status, ReadStatus::kFrame);
    ASSERT_EQ(frame.depth.cols, 640);
    ASSERT_EQ(frame.depth.type(), CV_16UC1);
    const auto entry = ClipImages::closest(clip.bgr, frame.bgr).first;
    const cv::Mat& truth = clip.depth_mm[entry];
    int measured = 0, same = 0;
    for (int v = 0; v < truth.rows; ++v)
      for (int u = 0; u < truth.cols; ++u) {
        if (truth.at<std::uint16_t>(v, u) == 0) continue;
        ++measured;
        same += std::abs(frame.depth.at<std::uint16_t>(v, u) - truth.at<std::uint16_t>(v, u)) <= 1;
      }
    // The emulator stretches depth by nearest neighbour (up to a pixel off), which moves depth edges.
    EXPECT_GT(same, measured * 8 / 10) << "frame " << i << " (clip entry " << entry << ")";
  }
}

TEST(EmulatedV4l2, SlowReaderLosesBuffersAndTheyAreCounted) {
  auto source = open_source("v4l2:" + kPlain, fr1_in_mm());
  core::RgbdFrame frame;
  ASSERT_EQ(read_frame(*source, frame).status, ReadStatus::kFrame);
  const auto lost_before = source->lost_frames();
  // Not reading for 30 frame periods: the driver fills its 4 buffers and drops the rest.
  std::this_thread::sleep_for(1s);
  for (int i = 0; i < 8; ++i) ASSERT_EQ(read_frame(*source, frame).status, ReadStatus::kFrame);
  const auto colour = emulator_stats(node(kPlain, 0)), depth = emulator_stats(node(kPlain, 1));
  EXPECT_GT(colour.dropped, 0u);
  EXPECT_GT(depth.dropped, 0u);
  EXPECT_GT(source->lost_frames(), lost_before) << "buffer sequence gaps are counted";
}

TEST(EmulatedV4l2, UnplugIsDisconnectionAndTheCameraIsReopened) {
  const ClipImages clip;
  ReconnectingSource source("v4l2:" + kReplugs, fr1_in_mm(), Backoff{20ms, 100ms, 2.0});
  core::RgbdFrame frame;
  int before = 0, after = 0, disconnections = 0;
  std::string why;
  for (int i = 0; i < 500 && after < 10; ++i) {
    const auto r = source.read(frame, cvo::testing::scaled(100ms));
    if (r.status == ReadStatus::kDisconnected) ++disconnections, why = r.message;
    if (r.status != ReadStatus::kFrame) continue;
    (disconnections == 0 ? before : after) += 1;
    const auto [entry, distance] = ClipImages::closest(clip.depth_mm, frame.depth);
    EXPECT_EQ(distance, 0) << "a frame of the clip after " << before << " + " << after;
  }
  EXPECT_GT(before, 0);
  EXPECT_LE(before, 20) << "the camera made 20 colour frames before it went";
  EXPECT_EQ(disconnections, 1) << why;
  EXPECT_EQ(after, 10) << "frames again after the camera came back";
  EXPECT_EQ(source.reconnects(), 1u);
  EXPECT_EQ(emulator_stats(node(kReplugs, 0)).unplugs, 1u);
  EXPECT_TRUE(why.find(node(kReplugs, 0)) != std::string::npos || why.find(node(kReplugs, 1)) != std::string::npos)
      << why;
}

TEST(EmulatedV4l2, FrameTheDriverMarksCorruptIsBadInputAndStreamingGoesOn) {
  auto source = open_source("v4l2:" + kCorrupt, fr1_in_mm());
  core::RgbdFrame frame;
  int frames = 0, corrupt = 0;
  for (int i = 0; i < 200 && (frames < 6 || corrupt < 2); ++i) {
    const auto r = source->read(frame, cvo::testing::scaled(200ms));
    if (r.status == ReadStatus::kFrame) ++frames;
    if (r.status != ReadStatus::kBadInput) continue;
    ++corrupt;
    EXPECT_EQ(r.bad_input, core::BadKind::kContent);
    EXPECT_NE(r.message.find(node(kCorrupt, 0) + ": the driver marks the frame corrupt"), std::string::npos)
        << r.message;
  }
  EXPECT_GE(frames, 6);
  EXPECT_GE(corrupt, 2) << "V4L2_BUF_FLAG_ERROR on every third colour frame";
}

// What a program with the emulator loaded says on stderr about CVO_V4L2_EMULATOR=`camera`.
std::string emulator_says(const std::string& camera) {
  const std::string command = "CVO_V4L2_EMULATOR='" + camera + "' /bin/true 2>&1";
  std::string out;
  if (FILE* pipe = ::popen(command.c_str(), "r")) {
    char buffer[1024];
    while (std::fgets(buffer, sizeof buffer, pipe) != nullptr) out += buffer;
    ::pclose(pipe);
  }
  return out;
}

TEST(EmulatedV4l2Config, ABadDescriptionIsReportedAndThatCameraIsNotEmulated) {
  EXPECT_EQ(emulator_says(""), "") << "no camera, nothing to say";
  EXPECT_NE(emulator_says("colour=/dev/video120,depth=/dev/video121,tum=" + cvo::testing::kEmulatedClip.string() +
                          ",depth_fps=fast")
                .find("cvo-v4l2-emulator: CVO_V4L2_EMULATOR ignored: depth_fps: 'fast' is not a number"),
            std::string::npos);
  EXPECT_NE(emulator_says("colour=/dev/video120,tum=x").find("colour=, depth= and tum= are required"),
            std::string::npos);
  EXPECT_NE(emulator_says("colour=/dev/video120,depth=/dev/video121,tum=x,fps=30").find("'fps=30': expected key=value"),
            std::string::npos);
  EXPECT_NE(emulator_says("colour=/dev/video120,depth=/dev/video121,tum=/nonexistent")
                .find("cvo-v4l2-emulator: camera not emulated: "),
            std::string::npos);
}

// Raw ioctls, as a V4L2 application other than ours would make them.
class Node {
 public:
  explicit Node(const std::string& path) : fd_(::open(path.c_str(), O_RDWR | O_NONBLOCK)) {}
  ~Node() {
    if (fd_ >= 0) ::close(fd_);
  }
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;
  [[nodiscard]] int fd() const { return fd_; }
  template <class T>
  int io(unsigned long request, T& arg) const {
    return ::ioctl(fd_, request, &arg) == 0 ? 0 : errno;
  }

 private:
  int fd_;
};

TEST(EmulatedV4l2Node, AnswersFormatQueriesAsUvcvideo) {
  Node depth(node(kD435, 1));
  ASSERT_GE(depth.fd(), 0) << std::strerror(errno);
  v4l2_capability cap{};
  ASSERT_EQ(depth.io(VIDIOC_QUERYCAP, cap), 0);
  EXPECT_STREQ(reinterpret_cast<const char*>(cap.driver), "uvcvideo");
  EXPECT_EQ(cap.device_caps, V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING | V4L2_CAP_EXT_PIX_FORMAT);
  EXPECT_NE(cap.capabilities & V4L2_CAP_DEVICE_CAPS, 0u);

  v4l2_fmtdesc desc{};
  desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  ASSERT_EQ(depth.io(VIDIOC_ENUM_FMT, desc), 0);
  EXPECT_EQ(desc.pixelformat, V4L2_PIX_FMT_Z16);
  desc.index = 1;
  EXPECT_EQ(depth.io(VIDIOC_ENUM_FMT, desc), EINVAL) << "one format";

  v4l2_frmsizeenum size{};
  size.pixel_format = V4L2_PIX_FMT_Z16;
  ASSERT_EQ(depth.io(VIDIOC_ENUM_FRAMESIZES, size), 0);
  EXPECT_EQ(size.type, V4L2_FRMSIZE_TYPE_DISCRETE);
  EXPECT_EQ(size.discrete.width, 848u);
  size.pixel_format = V4L2_PIX_FMT_YUYV;
  EXPECT_EQ(depth.io(VIDIOC_ENUM_FRAMESIZES, size), EINVAL);

  // S_FMT takes the closest size the camera has, and says so.
  v4l2_format f{};
  f.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  f.fmt.pix.width = 640;
  f.fmt.pix.height = 480;
  f.fmt.pix.pixelformat = V4L2_PIX_FMT_YUYV;
  ASSERT_EQ(depth.io(VIDIOC_S_FMT, f), 0);
  EXPECT_EQ(f.fmt.pix.pixelformat, V4L2_PIX_FMT_Z16) << "an unknown format becomes the node's";
  EXPECT_EQ(f.fmt.pix.width, 848u);
  EXPECT_EQ(f.fmt.pix.bytesperline, 848u * 2);
  EXPECT_EQ(f.fmt.pix.sizeimage, 848u * 480 * 2);

  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  parm.parm.capture.timeperframe = {1, 60};
  ASSERT_EQ(depth.io(VIDIOC_S_PARM, parm), 0);
  EXPECT_EQ(parm.parm.capture.timeperframe.denominator, 30u) << "the closest rate it has";
  EXPECT_EQ(parm.parm.capture.capability, V4L2_CAP_TIMEPERFRAME);

  char byte = 0;
  EXPECT_EQ(::read(depth.fd(), &byte, 1), -1);
  EXPECT_EQ(errno, EINVAL) << "uvcvideo has no read() I/O";
  v4l2_queryctrl control{};
  EXPECT_EQ(depth.io(VIDIOC_QUERYCTRL, control), ENOTTY) << "controls are not emulated";
}

// Maps and queues every buffer of `n` and starts streaming; the mappings are returned.
std::vector<std::pair<void*, std::size_t>> stream(const Node& n, unsigned count) {
  std::vector<std::pair<void*, std::size_t>> maps;
  v4l2_requestbuffers req{};
  req.count = count;
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  EXPECT_EQ(n.io(VIDIOC_REQBUFS, req), 0);
  for (unsigned i = 0; i < req.count; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = i;
    EXPECT_EQ(n.io(VIDIOC_QUERYBUF, b), 0);
    void* p = ::mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, n.fd(), b.m.offset);
    EXPECT_NE(p, MAP_FAILED) << std::strerror(errno);
    maps.emplace_back(p, b.length);
    EXPECT_EQ(n.io(VIDIOC_QBUF, b), 0);
    EXPECT_EQ(n.io(VIDIOC_QBUF, b), EINVAL) << "already queued";
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  EXPECT_EQ(n.io(VIDIOC_STREAMON, type), 0);
  return maps;
}

TEST(EmulatedV4l2Node, StreamsMonotonicTimestampsUntilUnpluggedThenEnodev) {
  Node colour(kLeaves);
  ASSERT_GE(colour.fd(), 0) << std::strerror(errno);
  Node other(kLeaves);
  const auto maps = stream(colour, 4);
  v4l2_requestbuffers req{};
  req.count = 4;
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  EXPECT_EQ(other.io(VIDIOC_REQBUFS, req), EBUSY) << "the queue belongs to the first file";

  std::vector<std::uint32_t> sequences;
  pollfd p{colour.fd(), POLLIN, 0};
  for (int i = 0; i < 200; ++i) {
    ASSERT_GE(::poll(&p, 1, 1000), 0);
    if ((p.revents & (POLLERR | POLLHUP)) != 0) break;
    if ((p.revents & POLLIN) == 0) continue;
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    ASSERT_EQ(colour.io(VIDIOC_DQBUF, b), 0);
    EXPECT_EQ(b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK, V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC);
    EXPECT_EQ(b.bytesused, 640u * 480 * 2);
    timespec now{};
    ::clock_gettime(CLOCK_MONOTONIC, &now);
    EXPECT_LE(b.timestamp.tv_sec, now.tv_sec) << "stamped on CLOCK_MONOTONIC, when it was made";
    EXPECT_GE(b.timestamp.tv_sec, now.tv_sec - 60);
    sequences.push_back(b.sequence);
    EXPECT_EQ(colour.io(VIDIOC_QBUF, b), 0);
  }
  EXPECT_EQ(p.revents & (POLLERR | POLLHUP), POLLERR | POLLHUP) << "an unregistered device's poll";
  ASSERT_FALSE(sequences.empty());
  for (std::size_t i = 1; i < sequences.size(); ++i) EXPECT_GT(sequences[i], sequences[i - 1]);
  EXPECT_LE(sequences.back(), 4u) << "unplugged after 5 frames";

  // Gone: every call but close is ENODEV, the node is gone from /dev, the mappings stay memory.
  v4l2_capability cap{};
  EXPECT_EQ(colour.io(VIDIOC_QUERYCAP, cap), ENODEV);
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  EXPECT_EQ(colour.io(VIDIOC_DQBUF, b), ENODEV);
  EXPECT_EQ(::mmap(nullptr, 4096, PROT_READ, MAP_SHARED, colour.fd(), 0), MAP_FAILED);
  EXPECT_EQ(errno, ENODEV);
  char byte = 0;
  EXPECT_EQ(::read(colour.fd(), &byte, 1), -1);
  EXPECT_EQ(errno, ENODEV);
  EXPECT_EQ(::open(kLeaves.c_str(), O_RDWR), -1);
  EXPECT_EQ(errno, ENOENT);
  for (const auto& [address, length] : maps) {
    const volatile std::uint8_t last = static_cast<const volatile std::uint8_t*>(address)[length - 1];  // no SIGBUS
    (void)last;
    EXPECT_EQ(::munmap(address, length), 0);
  }
  EXPECT_EQ(emulator_stats(kLeaves).unplugs, 1u);
}

}  // namespace
}  // namespace cvo::drivers
