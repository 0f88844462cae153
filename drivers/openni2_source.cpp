#include "drivers/openni2_source.hpp"

#include <openni2/OpenNI.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <chrono>
#include <climits>
#include <cmath>
#include <optional>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "drivers/frame_gaps.hpp"
#include "drivers/openni2_virtual/virtual_device.hpp"
#include "drivers/read_result.hpp"
#include "drivers/usb_cameras.hpp"

namespace cvo::drivers {
namespace {

using Clock = std::chrono::steady_clock;

// OpenNI's text ends in a newline; trimmed, so that more can follow on the same line.
std::string openni_error() {
  std::string text = std::string("OpenNI: ") + openni::OpenNI::getExtendedError();
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back())) != 0) text.pop_back();
  return text;
}

// OpenNI is one library per process (shutdown() forbids any later call), so it is initialised on
// first use and shut down at exit.
struct OpenNiLibrary {
  OpenNiLibrary() : status(openni::OpenNI::initialize()) {
    if (status != openni::STATUS_OK) error = openni_error();
  }
  ~OpenNiLibrary() {
    if (status == openni::STATUS_OK) openni::OpenNI::shutdown();
  }
  OpenNiLibrary(const OpenNiLibrary&) = delete;
  OpenNiLibrary& operator=(const OpenNiLibrary&) = delete;

  openni::Status status;
  std::string error;
};

void require_openni(const std::string& spec) {
  static const OpenNiLibrary library;
  if (library.status != openni::STATUS_OK) throw SourceError(spec, "OpenNI does not initialise: " + library.error);
}

std::string mode_text(const openni::VideoMode& m) {
  return std::to_string(m.getResolutionX()) + "x" + std::to_string(m.getResolutionY()) + "@" +
         std::to_string(m.getFps());
}

// The exact mode asked for, among those the sensor lists; the error lists them all.
openni::VideoMode find_mode(const openni::VideoStream& stream, openni::PixelFormat format, const SourceOptions& o,
                            const std::string& spec, const char* what) {
  const auto& modes = stream.getSensorInfo().getSupportedVideoModes();
  std::string offered;
  for (int i = 0; i < modes.getSize(); ++i) {
    const auto& m = modes[i];
    if (m.getPixelFormat() != format) continue;
    if (m.getResolutionX() == o.width && m.getResolutionY() == o.height && m.getFps() == o.fps) return m;
    offered += (offered.empty() ? "" : ", ") + mode_text(m);
  }
  throw SourceError(spec, std::string(what) + " has no mode " + std::to_string(o.width) + "x" +
                              std::to_string(o.height) + "@" + std::to_string(o.fps) +
                              " (offers: " + (offered.empty() ? "none" : offered) + ")");
}

// The device's own camera model when it gives one (the cvo-virtual driver does), else from the
// colour stream's fields of view with the principal point at the image centre.
core::Intrinsics device_intrinsics(openni::VideoStream& colour, int width, int height, double depth_scale) {
  core::Intrinsics k;
  k.width = width;
  k.height = height;
  k.depth_scale = depth_scale;
  namespace virt = virtual_device;
  if (virt::StreamIntrinsics own; colour.isPropertySupported(virt::kIntrinsicsProperty) &&
                                  colour.getProperty(virt::kIntrinsicsProperty, &own) == openni::STATUS_OK) {
    k.fx = own.fx;
    k.fy = own.fy;
    k.cx = own.cx;
    k.cy = own.cy;
    std::copy(std::begin(own.distortion), std::end(own.distortion), k.distortion.begin());
    k.readout_s = own.readout_s;
    return k;
  }
  // A float field of view holds about 7 digits, a focal length to some 1e-5 px: rounded to 1e-4 px
  // so that no digit is made up and a focal length given to 4 decimals (calibrations, the virtual
  // device's folders) comes back exactly.
  const auto focal = [](double size, float fov) { return std::round(size / 2.0 / std::tan(fov / 2.0) * 1e4) / 1e4; };
  k.fx = focal(width, colour.getHorizontalFieldOfView());
  k.fy = focal(height, colour.getVerticalFieldOfView());
  k.cx = width / 2.0;
  k.cy = height / 2.0;
  return k;
}

// Depth units per metre of OpenNI's depth formats; 0 for others.
double depth_units_per_metre(openni::PixelFormat format) {
  if (format == openni::PIXEL_FORMAT_DEPTH_1_MM) return 1000.0;
  if (format == openni::PIXEL_FORMAT_DEPTH_100_UM) return 10000.0;
  return 0.0;
}

// 1 mm depth from cameras (16 bits of 100 µm would end their range at 6.5 m); 100 µm from the
// virtual device, exact for TUM's 0.2 mm units, when it offers the mode asked for.
openni::VideoMode find_depth_mode(const openni::VideoStream& depth, const SourceOptions& o, const std::string& spec,
                                  bool fine) {
  const auto& modes = depth.getSensorInfo().getSupportedVideoModes();
  for (int i = 0; fine && i < modes.getSize(); ++i) {
    const auto& m = modes[i];
    if (m.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_100_UM && m.getResolutionX() == o.width &&
        m.getResolutionY() == o.height && m.getFps() == o.fps)
      return m;
  }
  return find_mode(depth, openni::PIXEL_FORMAT_DEPTH_1_MM, o, spec, "the depth sensor");
}

// OpenNI reports an unplugged device only through this callback (its streams just go quiet); a
// device that plays a recording (the cvo-virtual driver) says it has ended with the device state
// DEVICE_STATE_EOF. The callbacks run on OpenNI's or the driver's threads, hence the atomics.
class UnplugWatch final : public openni::OpenNI::DeviceDisconnectedListener,
                          public openni::OpenNI::DeviceStateChangedListener {
 public:
  UnplugWatch() = default;
  ~UnplugWatch() override {
    if (registered_) openni::OpenNI::removeDeviceDisconnectedListener(this);
    if (state_registered_) openni::OpenNI::removeDeviceStateChangedListener(this);
  }
  UnplugWatch(const UnplugWatch&) = delete;
  UnplugWatch& operator=(const UnplugWatch&) = delete;

  /// Once OpenNI is initialised and the device open.
  void watch(std::string uri) {
    uri_ = std::move(uri);
    registered_ = openni::OpenNI::addDeviceDisconnectedListener(this) == openni::STATUS_OK;
    state_registered_ = openni::OpenNI::addDeviceStateChangedListener(this) == openni::STATUS_OK;
  }
  void onDeviceDisconnected(const openni::DeviceInfo* info) override {
    if (info != nullptr && uri_ == info->getUri()) unplugged_ = true;
  }
  void onDeviceStateChanged(const openni::DeviceInfo* info, openni::DeviceState state) override {
    if (info != nullptr && uri_ == info->getUri() && state == openni::DEVICE_STATE_EOF) ended_ = true;
  }
  [[nodiscard]] bool unplugged() const { return unplugged_; }
  [[nodiscard]] bool ended() const { return ended_; }

 private:
  bool registered_ = false, state_registered_ = false;
  std::string uri_;  // set before the listener is registered, then only read
  std::atomic<bool> unplugged_{false}, ended_{false};
};

class OpenNi2Source final : public FrameSource {
 public:
  OpenNi2Source(std::string uri, const SourceOptions& options) : spec_("openni2:" + uri) {
    require_openni(spec_);
    const bool any = uri.empty() || uri == "any";
    if (device_.open(any ? openni::ANY_DEVICE : uri.c_str()) != openni::STATUS_OK)
      throw SourceError(spec_, "cannot open " + (any ? std::string("a device") : "'" + uri + "'") + ": " +
                                   openni_error() + "; " + usb_open_hint(spec_));
    watch_.watch(device_.getDeviceInfo().getUri());
    create(depth_, openni::SENSOR_DEPTH, "depth");
    create(colour_, openni::SENSOR_COLOR, "colour");

    if (auto* playback = device_.getPlaybackControl(); playback != nullptr) {
      // A recording plays once: realtime at its recorded rate, like the camera (without skipping
      // frames for a consumer that keeps up); else frame by frame as read (OpenNI's speed -1), so
      // that none is skipped.
      playback->setRepeatEnabled(false);
      playback->setSpeed(options.realtime ? 1.0f : -1.0f);
      frames_in_file_ = {playback->getNumberOfFrames(depth_), playback->getNumberOfFrames(colour_)};
    } else {
      set_mode(depth_, find_depth_mode(depth_, options, spec_, uri.starts_with(virtual_device::kScheme)));
      set_mode(colour_, find_mode(colour_, openni::PIXEL_FORMAT_RGB888, options, spec_, "the colour sensor"));
      // The virtual device can also play frame by frame; cameras have no such property.
      if (!options.realtime && device_.isPropertySupported(virtual_device::kPacedProperty))
        device_.setProperty(virtual_device::kPacedProperty, 0);
    }
    registered_ = device_.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) &&
                  device_.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) == openni::STATUS_OK;
    // Best effort: recordings and some drivers do not support these, and are fine without.
    device_.setDepthColorSyncEnabled(true);
    depth_.setMirroringEnabled(false);
    colour_.setMirroringEnabled(false);

    const auto depth_mode = depth_.getVideoMode(), colour_mode = colour_.getVideoMode();
    const double depth_scale = depth_units_per_metre(depth_mode.getPixelFormat());
    if (depth_scale == 0 || colour_mode.getPixelFormat() != openni::PIXEL_FORMAT_RGB888)
      throw SourceError(spec_, "needs 1 mm or 100 um depth and RGB888 colour (a recording of other formats?)");
    width_ = colour_mode.getResolutionX();
    height_ = colour_mode.getResolutionY();
    if (depth_mode.getResolutionX() != width_ || depth_mode.getResolutionY() != height_)
      throw SourceError(spec_, "depth is " + mode_text(depth_mode) + " but colour " + mode_text(colour_mode) +
                                   ": registered depth needs one size");
    intrinsics_ = options.intrinsics ? *options.intrinsics : device_intrinsics(colour_, width_, height_, depth_scale);
    intrinsics_.depth_scale = depth_scale;  // the stream's unit, whatever a camera file says
    if (const auto bad = intrinsics_.validate(); !bad.empty()) throw SourceError(spec_, "intrinsics: " + bad);
    if (intrinsics_.width != width_ || intrinsics_.height != height_)
      throw SourceError(spec_, "intrinsics are for " + std::to_string(intrinsics_.width) + "x" +
                                   std::to_string(intrinsics_.height) + " but the streams are " +
                                   mode_text(colour_mode));

    if (depth_.start() != openni::STATUS_OK) throw SourceError(spec_, "depth stream does not start: " + openni_error());
    if (colour_.start() != openni::STATUS_OK)
      throw SourceError(spec_, "colour stream does not start: " + openni_error());
  }

  ~OpenNi2Source() override {
    recorder_.destroy();  // closes the file; before the streams it records go
    colour_.stop();
    depth_.stop();
  }

  /// From now on OpenNI's own Recorder writes both streams, as the device sends them, to `file`
  /// (depth losslessly compressed, colour uncompressed).
  void record_to(const std::filesystem::path& file) {
    const auto fail = [&](const std::string& doing) { throw SourceError(file, doing + ": " + openni_error()); };
    if (recorder_.create(file.c_str()) != openni::STATUS_OK) fail("cannot create the recording");
    if (recorder_.attach(depth_, false) != openni::STATUS_OK) fail("cannot record the depth stream");
    if (recorder_.attach(colour_, false) != openni::STATUS_OK) fail("cannot record the colour stream");
    if (recorder_.start() != openni::STATUS_OK) fail("the recorder does not start");
  }
  OpenNi2Source(const OpenNi2Source&) = delete;
  OpenNi2Source& operator=(const OpenNi2Source&) = delete;

  ReadResult read(core::RgbdFrame& frame, std::chrono::milliseconds timeout) override {
    const auto deadline = Clock::now() + timeout;
    std::array<openni::VideoStream*, 2> streams{&depth_, &colour_};
    while (!(fresh_[0] && fresh_[1])) {
      if (recording_ended()) return result(ReadStatus::kEndOfStream);
      if (watch_.unplugged()) return result(ReadStatus::kDisconnected, spec_ + ": device unplugged");
      // Once the device has ended, only the frames it sent before are still to read.
      const bool ended = watch_.ended();
      const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()).count();
      int ready = -1;
      const auto status = openni::OpenNI::waitForAnyStream(
          streams.data(), 2, &ready, ended ? 0 : static_cast<int>(std::clamp<long long>(left, 0, INT_MAX)));
      if (status == openni::STATUS_TIME_OUT) return result(ended ? ReadStatus::kEndOfStream : ReadStatus::kTimeout);
      if (status != openni::STATUS_OK || ready < 0 || ready > 1) return disconnected("waiting for frames");
      const auto s = static_cast<std::size_t>(ready);
      if (streams[s]->readFrame(&frames_[s]) != openni::STATUS_OK || !frames_[s].isValid())
        return disconnected("reading a frame");
      if (fresh_[s]) ++replaced_;  // a second frame of one stream before one of the other
      fresh_[s] = true;
      gaps_[s].arrived(frames_[s].getFrameIndex());
      last_index_[s] = frames_[s].getFrameIndex();
    }
    fresh_ = {false, false};
    return convert(frame);
  }

  [[nodiscard]] std::string describe() const override {
    return spec_ + " (" + std::to_string(width_) + "x" + std::to_string(height_) + ", " +
           (device_.isFile() ? "recording" : "device") + (registered_ ? "" : ", depth not registered to colour") + ")";
  }

  [[nodiscard]] std::uint64_t lost_frames() const override {
    return std::max(gaps_[0].lost(), gaps_[1].lost()) + replaced_;
  }

 private:
  void create(openni::VideoStream& stream, openni::SensorType type, const char* name) {
    if (device_.getSensorInfo(type) == nullptr) throw SourceError(spec_, std::string("has no ") + name + " sensor");
    if (stream.create(device_, type) != openni::STATUS_OK)
      throw SourceError(spec_, std::string("cannot create the ") + name + " stream: " + openni_error());
  }

  void set_mode(openni::VideoStream& stream, const openni::VideoMode& mode) {
    if (stream.setVideoMode(mode) != openni::STATUS_OK)
      throw SourceError(spec_, "cannot set mode " + mode_text(mode) + ": " + openni_error());
  }

  // Recordings number their frames from 1; a stream whose last frame was read has no more.
  [[nodiscard]] bool recording_ended() const {
    if (!frames_in_file_) return false;
    for (std::size_t s = 0; s < 2; ++s)
      if (!fresh_[s] && last_index_[s] >= (*frames_in_file_)[s]) return true;
    return false;
  }

  ReadResult disconnected(const std::string& doing) const {
    return result(ReadStatus::kDisconnected, spec_ + ": " + doing + ": " + openni_error());
  }

  ReadResult convert(core::RgbdFrame& frame) {
    const auto& depth = frames_[0];
    const auto& colour = frames_[1];
    if (depth.getWidth() != width_ || depth.getHeight() != height_ || colour.getWidth() != width_ ||
        colour.getHeight() != height_)
      return bad_input(core::BadKind::kContent, spec_ + ": a frame of another size than the stream's " +
                                                    std::to_string(width_) + "x" + std::to_string(height_));
    // OpenNI's buffers are only borrowed: wrap them, convert or copy into the caller's images.
    const cv::Mat rgb(height_, width_, CV_8UC3, const_cast<void*>(colour.getData()),
                      static_cast<std::size_t>(colour.getStrideInBytes()));
    const cv::Mat mm(height_, width_, CV_16UC1, const_cast<void*>(depth.getData()),
                     static_cast<std::size_t>(depth.getStrideInBytes()));
    cv::cvtColor(rgb, frame.bgr, cv::COLOR_RGB2BGR);
    mm.copyTo(frame.depth);

    // Device time has an arbitrary zero: it is moved onto the system clock at the first frame.
    const double colour_s = static_cast<double>(colour.getTimestamp()) * 1e-6;
    if (!clock_offset_) {
      clock_offset_ =
          std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count() - colour_s;
    }
    frame.index = next_index_++;
    frame.timestamp = *clock_offset_ + colour_s;
    frame.depth_timestamp = *clock_offset_ + static_cast<double>(depth.getTimestamp()) * 1e-6;
    frame.intrinsics = intrinsics_;
    return result(ReadStatus::kFrame);
  }

  const std::string spec_;
  UnplugWatch watch_;
  openni::Device device_;  // declared first: the streams are destroyed before it closes
  openni::VideoStream depth_, colour_;
  openni::Recorder recorder_;                    // after the streams: destroyed before them
  std::array<openni::VideoFrameRef, 2> frames_;  // [0] depth, [1] colour, as in read()'s stream list
  std::array<bool, 2> fresh_{false, false};      // frames_[s] not yet returned
  std::array<int, 2> last_index_{0, 0};
  std::array<FrameGaps, 2> gaps_;
  std::uint64_t replaced_ = 0;
  std::optional<std::array<int, 2>> frames_in_file_;  // set for a recording
  bool registered_ = false;
  int width_ = 0, height_ = 0;
  core::Intrinsics intrinsics_;
  std::optional<double> clock_offset_;
  std::uint64_t next_index_ = 0;
};

}  // namespace

std::unique_ptr<FrameSource> open_openni2(std::string_view uri, const SourceOptions& options) {
  return std::make_unique<OpenNi2Source>(std::string(uri), options);
}

std::unique_ptr<FrameSource> open_openni2_recording(std::string_view uri, const std::filesystem::path& oni,
                                                    const SourceOptions& options) {
  auto source = std::make_unique<OpenNi2Source>(std::string(uri), options);
  source->record_to(oni);
  return source;
}

std::string openni2_version() {
  require_openni("openni2:");
  const auto v = openni::OpenNI::getVersion();
  return std::to_string(v.major) + "." + std::to_string(v.minor) + "." + std::to_string(v.maintenance) + "." +
         std::to_string(v.build);
}

}  // namespace cvo::drivers
