#include "drivers/openni2_source.hpp"

#include <openni2/OpenNI.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <optional>

#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "drivers/depth_registration.hpp"
#include "drivers/frame_gaps.hpp"
#include "drivers/oni_file.hpp"
#include "drivers/openni2_camera_model.hpp"
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
  if (text == "OpenNI:") text += " (no reason given)";
  return text;
}

// A recording that was never closed, played from a repaired copy (oni_file.hpp) that goes with the
// source: OpenNI's player refuses the original although its frames are all there.
class RepairedCopy {
 public:
  RepairedCopy() = default;
  ~RepairedCopy() {
    std::error_code ec;
    if (!path_.empty()) std::filesystem::remove(path_, ec);
  }
  RepairedCopy(const RepairedCopy&) = delete;
  RepairedCopy& operator=(const RepairedCopy&) = delete;

  /// Writes the copy into the temporary directory and returns its path.
  const std::filesystem::path& make(const std::filesystem::path& file, const OniFileState& state) {
    static std::atomic<unsigned> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("cvo-repaired-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".oni");
    repair_oni_copy(file, state, path_);
    return path_;
  }

 private:
  std::filesystem::path path_;
};

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

// Colour: the mode asked for, else the largest smaller one at the rate (a camera whose colour
// streams smaller than its depth, e.g. QVGA colour beside VGA depth to save USB bandwidth; depth
// is then brought to colour's size).
openni::VideoMode find_colour_mode(const openni::VideoStream& colour, const SourceOptions& o, const std::string& spec) {
  const auto& modes = colour.getSensorInfo().getSupportedVideoModes();
  std::optional<openni::VideoMode> smaller;
  for (int i = 0; i < modes.getSize(); ++i) {
    const auto& m = modes[i];
    if (m.getPixelFormat() != openni::PIXEL_FORMAT_RGB888 || m.getFps() != o.fps) continue;
    if (m.getResolutionX() > o.width || m.getResolutionY() > o.height) continue;
    if (!smaller || m.getResolutionX() > smaller->getResolutionX()) smaller = m;
  }
  if (smaller) return *smaller;
  return find_mode(colour, openni::PIXEL_FORMAT_RGB888, o, spec, "the colour sensor");  // throws, listing them
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
  /// need_intrinsics false: a recorder, which records what the camera sends whether or not it says
  /// its intrinsics (its frames then carry none).
  OpenNi2Source(std::string uri, const SourceOptions& options, bool need_intrinsics = true) : spec_("openni2:" + uri) {
    require_openni(spec_);
    open_device(uri);
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
      set_mode(colour_, find_colour_mode(colour_, options, spec_));
      // The virtual device can also play frame by frame; cameras have no such property.
      if (!options.realtime && device_.isPropertySupported(virtual_device::kPacedProperty))
        device_.setProperty(virtual_device::kPacedProperty, 0);
    }
    registered_ = device_.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) &&
                  device_.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) == openni::STATUS_OK;
    // Best effort: recordings and some drivers do not support these, and are fine without. A
    // stream that stays mirrored (a recording made mirrored) is flipped back in convert().
    device_.setDepthColorSyncEnabled(true);
    depth_.setMirroringEnabled(false);
    colour_.setMirroringEnabled(false);
    mirrored_ = {depth_.getMirroringEnabled(), colour_.getMirroringEnabled()};
    set_up_images(options, need_intrinsics);
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
    std::string d = spec_ + " (" + std::to_string(width_) + "x" + std::to_string(height_) + ", " +
                    (device_.isFile() ? "recording" : "device");
    if (file_ && !file_->closed) d += ", " + file_->summary() + ": played from a repaired copy";
    if (registration_)
      d += ", depth " + std::to_string(depth_width_) + "x" + std::to_string(depth_height_) +
           " registered to colour (the camera file's depth_sensor)";
    else if (depth_width_ != width_ || depth_height_ != height_)
      d += ", depth " + std::to_string(depth_width_) + "x" + std::to_string(depth_height_) +
           (registered_ ? " registered by the device, scaled to colour's size"
                        : " scaled to colour's size (ASSUMED registered by the device)");
    else if (!registered_ && !device_.isFile())
      d += ", depth not registered to colour";
    if (mirrored_[0] || mirrored_[1]) d += ", mirrored (flipped back)";
    char focal[64];
    std::snprintf(focal, sizeof(focal), "fx %.4f fy %.4f cx %.2f cy %.2f", intrinsics_.fx, intrinsics_.fy,
                  intrinsics_.cx, intrinsics_.cy);
    return d + ", intrinsics " + focal + " from " + intrinsics_source_ + ")";
  }

  [[nodiscard]] std::uint64_t lost_frames() const override {
    return std::max(gaps_[0].lost(), gaps_[1].lost()) + replaced_;
  }

 private:
  // A file is checked first (OpenNI gives no reason for what it cannot play) and a recording that
  // was never closed is played from a repaired copy; a device that fails is explained by libusb.
  void open_device(const std::string& uri) {
    const bool any = uri.empty() || uri == "any";
    std::string target = any ? std::string() : uri;
    if (!any && !uri.starts_with(virtual_device::kScheme) && is_oni_path(uri)) {
      file_ = inspect_oni(uri);
      if (!file_->problem.empty()) throw SourceError(spec_, "'" + uri + "': " + file_->problem);
      if (file_->needs_repair()) target = repaired_.make(uri, *file_).string();
      if (device_.open(target.c_str()) != openni::STATUS_OK)
        throw SourceError(spec_,
                          "cannot open the recording '" + uri + "' (" + file_->summary() + "): " + openni_error());
      return;
    }
    if (device_.open(any ? openni::ANY_DEVICE : target.c_str()) != openni::STATUS_OK)
      throw SourceError(spec_, "cannot open " + (any ? std::string("a device") : "'" + uri + "'") + ": " +
                                   openni_error() + "; " + usb_open_hint(spec_));
  }

  // False when the camera says nothing of its intrinsics and they are not needed (a recorder).
  bool choose_intrinsics(const SourceOptions& options, double depth_scale, bool needed) {
    try {
      auto model = openni2_camera_model(device_, depth_, colour_, width_, height_, options.intrinsics, spec_);
      intrinsics_ = model.intrinsics;
      intrinsics_source_ = std::move(model.origin);
    } catch (const SourceError&) {
      if (needed) throw;
      intrinsics_source_ = "nothing: the camera says none";
      return false;
    }
    intrinsics_.depth_scale = depth_scale;  // the stream's unit, whatever a camera file says
    if (const auto bad = intrinsics_.validate(); !bad.empty())
      throw SourceError(spec_, "intrinsics (from " + intrinsics_source_ + "): " + bad);
    if (intrinsics_.width != width_ || intrinsics_.height != height_)
      throw SourceError(spec_, "intrinsics are for " + std::to_string(intrinsics_.width) + "x" +
                                   std::to_string(intrinsics_.height) + " but the streams are " +
                                   std::to_string(width_) + "x" + std::to_string(height_));
    return true;
  }

  // The frame's size (colour's), its intrinsics, and how depth of another size comes to it.
  void set_up_images(const SourceOptions& options, bool need_intrinsics) {
    const auto depth_mode = depth_.getVideoMode(), colour_mode = colour_.getVideoMode();
    const double depth_scale = depth_units_per_metre(depth_mode.getPixelFormat());
    if (depth_scale == 0 || colour_mode.getPixelFormat() != openni::PIXEL_FORMAT_RGB888)
      throw SourceError(spec_, "needs 1 mm or 100 um depth and RGB888 colour (a recording of other formats?)");
    width_ = colour_mode.getResolutionX();
    height_ = colour_mode.getResolutionY();
    depth_width_ = depth_mode.getResolutionX();
    depth_height_ = depth_mode.getResolutionY();
    if (!choose_intrinsics(options, depth_scale, need_intrinsics)) return;
    // Depth the device registered (DEPTH_TO_COLOR) is never registered twice; otherwise the camera
    // file's depth sensor, when given, registers it whatever its size.
    if (!registered_ && options.depth_sensor) {
      registration_.emplace(*options.depth_sensor, intrinsics_);
      return;
    }
    if (depth_width_ == width_ && depth_height_ == height_) return;
    // Depth the device registered to colour covers colour's view at its own size: brought to
    // colour's size pixel for pixel (nearest, so no depth is made up between surfaces).
    if (static_cast<long>(depth_width_) * height_ != static_cast<long>(width_) * depth_height_)
      throw SourceError(spec_, "depth is " + mode_text(depth_mode) + " but colour " + mode_text(colour_mode) +
                                   ", another aspect ratio: registering it needs the depth sensor's calibration "
                                   "(a camera file with a depth_sensor section, --set camera=FILE.yaml)");
  }

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
    for (std::size_t s = 0; s < 2; ++s)  // a count of 0 or less: unknown (a repaired recording)
      if ((*frames_in_file_)[s] > 0 && !fresh_[s] && last_index_[s] >= (*frames_in_file_)[s]) return true;
    return false;
  }

  ReadResult disconnected(const std::string& doing) const {
    return result(ReadStatus::kDisconnected, spec_ + ": " + doing + ": " + openni_error());
  }

  ReadResult convert(core::RgbdFrame& frame) {
    const auto& depth = frames_[0];
    const auto& colour = frames_[1];
    if (depth.getWidth() != depth_width_ || depth.getHeight() != depth_height_ || colour.getWidth() != width_ ||
        colour.getHeight() != height_)
      return bad_input(core::BadKind::kContent, spec_ + ": a frame of another size than the stream's " +
                                                    std::to_string(width_) + "x" + std::to_string(height_));
    // OpenNI's buffers are only borrowed: wrap them, convert or copy into the caller's images.
    const cv::Mat rgb(height_, width_, CV_8UC3, const_cast<void*>(colour.getData()),
                      static_cast<std::size_t>(colour.getStrideInBytes()));
    const cv::Mat mm(depth_height_, depth_width_, CV_16UC1, const_cast<void*>(depth.getData()),
                     static_cast<std::size_t>(depth.getStrideInBytes()));
    cv::cvtColor(rgb, frame.bgr, cv::COLOR_RGB2BGR);
    if (mirrored_[1]) cv::flip(frame.bgr, frame.bgr, 1);
    const cv::Mat* raw = &mm;
    if (mirrored_[0]) {  // unflipped before registration: the depth sensor's own image
      cv::flip(mm, unmirrored_, 1);
      raw = &unmirrored_;
    }
    if (registration_)
      registration_->apply(*raw, frame.depth);
    else if (raw->cols != width_ || raw->rows != height_)
      cv::resize(*raw, frame.depth, cv::Size(width_, height_), 0, 0, cv::INTER_NEAREST);
    else
      raw->copyTo(frame.depth);

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
  std::optional<OniFileState> file_;  // a recording's state, as read before OpenNI opened it
  RepairedCopy repaired_;             // before the device: removed after it closes
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
  std::array<bool, 2> mirrored_{false, false};  // [0] depth, [1] colour: the stream stays mirrored
  int width_ = 0, height_ = 0, depth_width_ = 0, depth_height_ = 0;
  core::Intrinsics intrinsics_;
  std::string intrinsics_source_;
  std::optional<DepthRegistration> registration_;  // depth of a separate sensor (camera file)
  cv::Mat unmirrored_;                             // reused: no allocation per frame
  std::optional<double> clock_offset_;
  std::uint64_t next_index_ = 0;
};

}  // namespace

std::unique_ptr<FrameSource> open_openni2(std::string_view uri, const SourceOptions& options) {
  return std::make_unique<OpenNi2Source>(std::string(uri), options);
}

std::unique_ptr<FrameSource> open_openni2_recording(std::string_view uri, const std::filesystem::path& oni,
                                                    const SourceOptions& options) {
  auto source = std::make_unique<OpenNi2Source>(std::string(uri), options, false);
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
