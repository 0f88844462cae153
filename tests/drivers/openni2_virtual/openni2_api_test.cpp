// The virtual device as any OpenNI2 application sees it, through OpenNI2's own C++ API and the real
// runtime: sensors and video modes, fields of view, registration and frame sync, mirroring, device
// timestamps, frame indices, the end of the folder and an unplug with its return.
#include <openni2/OpenNI.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "drivers/openni2_virtual/virtual_device.hpp"
#include "libcvo/io/tum_dataset.hpp"

namespace cvo::drivers {
namespace {

namespace fs = std::filesystem;
namespace virt = virtual_device;

const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";

// OpenNI once per test program, as the library allows.
class OpenNiEnvironment : public ::testing::Environment {
 public:
  void SetUp() override {
    ASSERT_EQ(openni::OpenNI::initialize(), openni::STATUS_OK) << openni::OpenNI::getExtendedError();
  }
  void TearDown() override { openni::OpenNI::shutdown(); }
};
const auto* const kEnvironment = ::testing::AddGlobalTestEnvironment(new OpenNiEnvironment);

bool has_mode(const openni::SensorInfo& info, openni::PixelFormat format, int w, int h, int fps) {
  const auto& modes = info.getSupportedVideoModes();
  for (int i = 0; i < modes.getSize(); ++i)
    if (modes[i].getPixelFormat() == format && modes[i].getResolutionX() == w && modes[i].getResolutionY() == h &&
        modes[i].getFps() == fps)
      return true;
  return false;
}

// Reads one frame of `stream`, waiting (without a timed assertion) up to 10 s.
bool read_one(openni::VideoStream& stream, openni::VideoFrameRef& frame) {
  openni::VideoStream* streams[] = {&stream};
  int ready = -1;
  return openni::OpenNI::waitForAnyStream(streams, 1, &ready, 10000) == openni::STATUS_OK &&
         stream.readFrame(&frame) == openni::STATUS_OK;
}

TEST(VirtualDeviceApi, AnyDeviceIsStillARealCamera) {
  // The driver lists no device of its own (first in this file: later tests open some).
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  for (int i = 0; i < devices.getSize(); ++i)
    EXPECT_NE(std::string(devices[i].getVendor()), "cvo-slam") << devices[i].getUri() << " listed unasked";
}

TEST(VirtualDeviceApi, IsAPrimeSenseLikeDevice) {
  const std::string uri = "cvo-virtual:" + kClip.string();
  openni::Device device;
  ASSERT_EQ(device.open(uri.c_str()), openni::STATUS_OK) << openni::OpenNI::getExtendedError();
  EXPECT_EQ(std::string(device.getDeviceInfo().getUri()), uri) << "the URI names what it plays";
  EXPECT_EQ(std::string(device.getDeviceInfo().getVendor()), "cvo-slam");
  EXPECT_FALSE(device.isFile());

  const auto* depth_info = device.getSensorInfo(openni::SENSOR_DEPTH);
  const auto* colour_info = device.getSensorInfo(openni::SENSOR_COLOR);
  ASSERT_NE(depth_info, nullptr);
  ASSERT_NE(colour_info, nullptr);
  EXPECT_EQ(device.getSensorInfo(openni::SENSOR_IR), nullptr);
  EXPECT_TRUE(has_mode(*depth_info, openni::PIXEL_FORMAT_DEPTH_1_MM, 640, 480, 30));
  EXPECT_TRUE(has_mode(*depth_info, openni::PIXEL_FORMAT_DEPTH_100_UM, 640, 480, 30));
  EXPECT_TRUE(has_mode(*colour_info, openni::PIXEL_FORMAT_RGB888, 640, 480, 30));

  // Registration: TUM depth is registered already, both modes are accepted.
  EXPECT_TRUE(device.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR));
  EXPECT_EQ(device.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR), openni::STATUS_OK);
  EXPECT_EQ(device.getImageRegistrationMode(), openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR);

  openni::VideoStream depth, colour;
  ASSERT_EQ(depth.create(device, openni::SENSOR_DEPTH), openni::STATUS_OK);
  ASSERT_EQ(colour.create(device, openni::SENSOR_COLOR), openni::STATUS_OK);
  EXPECT_EQ(device.setDepthColorSyncEnabled(true), openni::STATUS_OK);

  // Fields of view from the folder's camera (fr1: fx 517.3, fy 516.5).
  const auto k = io::TumSequence::open(kClip).intrinsics();
  EXPECT_NEAR(colour.getHorizontalFieldOfView(), 2 * std::atan(640 / (2 * k.fx)), 1e-6);
  EXPECT_NEAR(colour.getVerticalFieldOfView(), 2 * std::atan(480 / (2 * k.fy)), 1e-6);
  virt::StreamIntrinsics own;
  ASSERT_EQ(colour.getProperty(virt::kIntrinsicsProperty, &own), openni::STATUS_OK);
  EXPECT_EQ(own.cx, k.cx);

  // A mode it does not have is refused; mirroring is a setting.
  openni::VideoMode qvga = colour.getVideoMode();
  qvga.setResolution(320, 240);
  EXPECT_NE(colour.setVideoMode(qvga), openni::STATUS_OK);
  EXPECT_EQ(colour.setMirroringEnabled(false), openni::STATUS_OK);
  EXPECT_FALSE(colour.getMirroringEnabled());
  EXPECT_EQ(colour.setMirroringEnabled(true), openni::STATUS_OK);
  EXPECT_TRUE(colour.getMirroringEnabled());
  EXPECT_EQ(colour.setMirroringEnabled(false), openni::STATUS_OK);
}

TEST(VirtualDeviceApi, FramesCarryTheRecordingsTimeIndexAndMirroring) {
  const auto tum = io::TumSequence::open(kClip);
  const std::string uri = "cvo-virtual:" + kClip.string() + "?unplug_after=1000";  // its own playback
  openni::Device device;
  ASSERT_EQ(device.open(uri.c_str()), openni::STATUS_OK) << openni::OpenNI::getExtendedError();
  ASSERT_EQ(device.setProperty(virt::kPacedProperty, 0), openni::STATUS_OK);  // frame by frame
  openni::VideoStream colour;
  ASSERT_EQ(colour.create(device, openni::SENSOR_COLOR), openni::STATUS_OK);
  ASSERT_EQ(colour.start(), openni::STATUS_OK);

  openni::VideoFrameRef frame;
  ASSERT_TRUE(read_one(colour, frame));
  EXPECT_EQ(frame.getFrameIndex(), 1);
  EXPECT_EQ(frame.getTimestamp(), static_cast<std::uint64_t>(std::llround(tum.files()[0].timestamp * 1e6)));
  const auto first = tum.read(0);
  const auto* rgb = static_cast<const std::uint8_t*>(frame.getData());
  const auto& bgr = first.bgr.at<cv::Vec3b>(10, 0);
  EXPECT_EQ(rgb[(10 * 640) * 3 + 0], bgr[2]);  // red first
  EXPECT_EQ(rgb[(10 * 640) * 3 + 2], bgr[0]);

  ASSERT_EQ(colour.setMirroringEnabled(true), openni::STATUS_OK);
  ASSERT_TRUE(read_one(colour, frame));
  EXPECT_EQ(frame.getFrameIndex(), 2) << "frame by frame: none skipped";
  const auto second = tum.read(1);
  rgb = static_cast<const std::uint8_t*>(frame.getData());
  const auto& right = second.bgr.at<cv::Vec3b>(10, 639);
  EXPECT_EQ(rgb[(10 * 640) * 3 + 0], right[2]) << "mirrored: the rightmost pixel comes first";
  EXPECT_EQ(rgb[(10 * 640) * 3 + 1], right[1]);
  colour.stop();
}

// Counts OpenNI's device events for one URI (they arrive on the virtual device's threads).
class Events final : public openni::OpenNI::DeviceConnectedListener,
                     public openni::OpenNI::DeviceDisconnectedListener,
                     public openni::OpenNI::DeviceStateChangedListener {
 public:
  explicit Events(std::string uri) : uri_(std::move(uri)) {
    openni::OpenNI::addDeviceConnectedListener(this);
    openni::OpenNI::addDeviceDisconnectedListener(this);
    openni::OpenNI::addDeviceStateChangedListener(this);
  }
  ~Events() override {
    openni::OpenNI::removeDeviceConnectedListener(this);
    openni::OpenNI::removeDeviceDisconnectedListener(this);
    openni::OpenNI::removeDeviceStateChangedListener(this);
  }
  Events(const Events&) = delete;
  Events& operator=(const Events&) = delete;
  void onDeviceConnected(const openni::DeviceInfo* info) override { connected += uri_ == info->getUri(); }
  void onDeviceDisconnected(const openni::DeviceInfo* info) override { disconnected += uri_ == info->getUri(); }
  void onDeviceStateChanged(const openni::DeviceInfo* info, openni::DeviceState state) override {
    ended += uri_ == info->getUri() && state == openni::DEVICE_STATE_EOF;
  }
  std::atomic<int> connected{0}, disconnected{0}, ended{0};

 private:
  std::string uri_;
};

// Waits (no timed assertion: up to 30 s, then the test fails on the value) for a counter.
bool eventually(const std::atomic<int>& counter, int value) {
  for (int i = 0; i < 3000 && counter.load() < value; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  return counter.load() >= value;
}

TEST(VirtualDeviceApi, UnplugsAfterNFramesComesBackAndEnds) {
  const std::string uri = "cvo-virtual:" + kClip.string() + "?unplug_after=3&replug_after_s=0.2";
  Events events(uri);
  int total = 0;
  {
    openni::Device device;
    ASSERT_EQ(device.open(uri.c_str()), openni::STATUS_OK) << openni::OpenNI::getExtendedError();
    EXPECT_EQ(events.connected.load(), 1);
    openni::VideoStream depth;
    ASSERT_EQ(depth.create(device, openni::SENSOR_DEPTH), openni::STATUS_OK);
    ASSERT_EQ(depth.start(), openni::STATUS_OK);
    openni::VideoFrameRef frame;
    for (int i = 0; i < 3; ++i) {
      ASSERT_TRUE(read_one(depth, frame)) << i;
      EXPECT_EQ(frame.getFrameIndex(), i + 1);
    }
    total = 3;
    ASSERT_TRUE(eventually(events.disconnected, 1)) << "unplugged after 3 frames";
    openni::Device again;
    EXPECT_NE(again.open(uri.c_str()), openni::STATUS_OK) << "gone while unplugged";
    depth.stop();
  }
  ASSERT_TRUE(eventually(events.connected, 2)) << "back after 0.2 s";
  openni::Device device;
  ASSERT_EQ(device.open(uri.c_str()), openni::STATUS_OK) << openni::OpenNI::getExtendedError();
  device.setProperty(virt::kPacedProperty, 0);
  openni::VideoStream depth;
  ASSERT_EQ(depth.create(device, openni::SENSOR_DEPTH), openni::STATUS_OK);
  ASSERT_EQ(depth.start(), openni::STATUS_OK);
  openni::VideoFrameRef frame;
  ASSERT_TRUE(read_one(depth, frame));
  EXPECT_EQ(frame.getFrameIndex(), 4) << "it goes on with the next frame";
  for (total = 4; total < 50; ++total) ASSERT_TRUE(read_one(depth, frame)) << total;
  EXPECT_EQ(frame.getFrameIndex(), 50);
  // Frame by frame, the device finds the end when asked for one more.
  openni::VideoStream* streams[] = {&depth};
  int ready = -1;
  EXPECT_EQ(openni::OpenNI::waitForAnyStream(streams, 1, &ready, 100), openni::STATUS_TIME_OUT) << "no 51st frame";
  EXPECT_TRUE(eventually(events.ended, 1)) << "DEVICE_STATE_EOF at the end of the folder";
  EXPECT_EQ(events.disconnected.load(), 1);
  depth.stop();
}

}  // namespace
}  // namespace cvo::drivers
