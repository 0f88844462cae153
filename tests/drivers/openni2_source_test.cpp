// openni2: no camera is attached to the machines that run these tests, so what is checked is what
// happens without one: OpenNI initialises, opening is a SourceError with OpenNI's own explanation,
// and the reconnecting wrapper keeps trying without ever blocking a read past its timeout.
#include <chrono>

#include <gtest/gtest.h>

#include "drivers/frame_source.hpp"
#include "drivers/open_source.hpp"
#include "drivers/openni2_source.hpp"
#include "drivers/reconnecting_source.hpp"

namespace cvo::drivers {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

TEST(OpenNI2Source, LibraryInitialises) {
  const auto version = openni2_version();
  EXPECT_EQ(version.rfind("2.", 0), 0u) << version;
}

TEST(OpenNI2Source, NoDeviceIsSourceErrorWithOpenNIsReason) {
  for (const std::string spec : {"openni2:", "openni2:any"}) {
    try {
      open_source(spec);
      GTEST_SKIP() << spec << " opened: a device is attached to this machine";
    } catch (const SourceError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("OpenNI"), std::string::npos) << what;
      EXPECT_NE(what.find(spec), std::string::npos) << what;
    }
  }
}

// A file is no device: what is wrong with it is said of the file, never of USB (issue 49).
TEST(OpenNI2Source, AMissingRecordingIsSourceErrorSayingSoWithoutUsb) {
  const std::string spec = "openni2:/no/such/recording.oni";
  try {
    open_source(spec);
    FAIL() << "opened a missing file";
  } catch (const SourceError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(spec), std::string::npos) << what;
    EXPECT_NE(what.find("no such file"), std::string::npos) << what;
    EXPECT_EQ(what.find("libusb"), std::string::npos) << what;
    EXPECT_EQ(what.find("USB"), std::string::npos) << what;
  }
  EXPECT_FALSE(names_device(spec)) << "a file is not re-opened with back-off";
  EXPECT_TRUE(names_device("openni2:any"));
  EXPECT_TRUE(names_device("openni2:cvo-virtual:/some/folder.oni"));
  EXPECT_TRUE(names_device("v4l2:/dev/video0,/dev/video1"));
  EXPECT_FALSE(names_device("tum:/data/fr1"));
}

TEST(OpenNI2Source, ReconnectingWrapperRetriesWithinTheTimeout) {
  try {
    open_source("openni2:");
    GTEST_SKIP() << "a device is attached to this machine";
  } catch (const SourceError&) {
  }
  ReconnectingSource source("openni2:", SourceOptions{}, Backoff{milliseconds(10), milliseconds(40), 2.0});
  core::RgbdFrame frame;
  const milliseconds timeout(60);
  const double slack_s = 0.5;  // scheduling on a loaded machine, and one open attempt

  auto start = Clock::now();
  const auto first = source.read(frame, timeout);
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - start).count(), 0.06 + slack_s);
  EXPECT_EQ(first.status, ReadStatus::kDisconnected);
  EXPECT_NE(first.message.find("OpenNI"), std::string::npos) << first.message;

  for (int i = 0; i < 8; ++i) {
    start = Clock::now();
    const auto r = source.read(frame, timeout);
    EXPECT_EQ(r.status, ReadStatus::kTimeout) << "still the same gap";
    EXPECT_NE(r.message.find("OpenNI"), std::string::npos) << r.message;
    EXPECT_LT(std::chrono::duration<double>(Clock::now() - start).count(), 0.06 + slack_s);
  }
  EXPECT_EQ(source.open_attempts(), 9u) << "each read was due one attempt (waits of 10, 20, 40, 40, ... ms)";
  EXPECT_FALSE(source.connected());
  EXPECT_EQ(source.gap_count(), 1u);
  EXPECT_EQ(source.reconnects(), 0u);
  EXPECT_GE(source.disconnected_time(), milliseconds(200));  // at least the waits: 10 + 20 + 40 + 40 + ...
  EXPECT_NE(source.describe().find("disconnected"), std::string::npos) << source.describe();
}

}  // namespace
}  // namespace cvo::drivers
