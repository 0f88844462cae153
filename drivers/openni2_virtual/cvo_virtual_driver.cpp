// The cvo-virtual OpenNI2 driver: a plug-in (OniDriverAPI) that the real OpenNI2 runtime loads from
// its drivers repository and that plays a TUM folder as a PrimeSense-like device, so that any
// OpenNI2 application (cvo-trackerd's openni2: source, cvo-oni-record, OpenNI's own tools) runs
// on a recording without a camera. URI and private properties: virtual_device.hpp.
//
// The device offers a depth sensor (100 µm and 1 mm modes) and a colour sensor (RGB888), each at
// the folder's image size and frame rate; fields of view from the folder's intrinsics; depth
// already registered to colour (as TUM's is), so both registration modes are accepted; mirroring;
// frame sync (both images of a frame carry one frame index); device timestamps that are the
// recording's own, in microseconds. It plays at the recorded rate, or frame by frame on OpenNI's
// manual trigger (kPacedProperty 0). At the end of the folder it reports ONI_DEVICE_STATE_EOF;
// with unplug_after it disconnects, and with replug_after_s it connects again, going on with the
// frame after the last one it played.
//
// OpenNI2 asks a driver for a device it does not list through tryDevice(uri): this driver lists
// nothing by itself (so "any device" still means a real camera) and answers only its own URIs.
#include <Driver/OniDriverAPI.h>
#include <PS1080.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "drivers/openni2_virtual/virtual_device.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/io/tum_dataset.hpp"

// ONI_EXPORT_DRIVER allocates the driver object with OpenNI's XnLib macros, which Debian's headers
// do not ship: plain new/delete are what they expand to.
#define XN_NEW(type, arg) new type(arg)
#define XN_DELETE(p) delete (p)

namespace cvo::drivers::virtual_device {
namespace {

using Clock = std::chrono::steady_clock;

// One recording behind one URI, shared by the successive connections of its device: where the
// playback is and whether the device is plugged in. The mutable part is guarded by the driver's
// mutex.
struct Playback {
  Playback(std::string device_uri, Uri parsed, io::TumSequence tum)
      : uri(std::move(device_uri)), options(std::move(parsed)), sequence(std::move(tum)) {
    std::strncpy(info.uri, uri.c_str(), ONI_MAX_STR - 1);
    std::strncpy(info.vendor, "cvo-slam", ONI_MAX_STR - 1);
    std::strncpy(info.name, "virtual TUM device", ONI_MAX_STR - 1);
    const auto& k = sequence.intrinsics();
    intrinsics = {k.fx, k.fy, k.cx, k.cy, {}, k.readout_s};
    std::copy(k.distortion.begin(), k.distortion.end(), std::begin(intrinsics.distortion));
    fps = frame_rate(sequence);
  }

  // The recording's mean rate, as the nominal rate a camera's mode would name: the nearest of
  // the usual ones (TUM's stamps jitter around 30 Hz).
  static int frame_rate(const io::TumSequence& s) {
    if (s.size() < 2) return 30;
    const double span = s.files().back().timestamp - s.files().front().timestamp;
    if (span <= 0) return 30;
    const double rate = static_cast<double>(s.size() - 1) / span;
    int best = 30;
    for (const int nominal : {1, 2, 5, 6, 10, 15, 20, 24, 25, 30, 50, 60, 90, 100, 120})
      if (std::abs(std::log(rate / nominal)) < std::abs(std::log(rate / best))) best = nominal;
    return best;
  }

  const std::string uri;
  const Uri options;
  const io::TumSequence sequence;  // only its const, thread-safe read(i) is used
  OniDeviceInfo info{};
  StreamIntrinsics intrinsics;
  int fps = 30;

  std::size_t next = 0;      // the frame to play next
  std::uint64_t played = 0;  // frames played, over all connections
  bool unplugged = false;    // between an unplug and its replug
  bool unplug_done = false;  // unplug_after acts once
};

[[nodiscard]] int width_of(const Playback& p) { return p.sequence.intrinsics().width; }
[[nodiscard]] int height_of(const Playback& p) { return p.sequence.intrinsics().height; }
// Colour's size: the folder's, or the colour_size option's.
[[nodiscard]] int colour_width_of(const Playback& p) {
  return p.options.colour_size ? p.options.colour_size->first : width_of(p);
}
[[nodiscard]] int colour_height_of(const Playback& p) {
  return p.options.colour_size ? p.options.colour_size->second : height_of(p);
}

template <class T>
OniStatus put(void* data, int* size, const T& value) {
  if (data == nullptr || size == nullptr || *size < static_cast<int>(sizeof(T))) return ONI_STATUS_BAD_PARAMETER;
  std::memcpy(data, &value, sizeof(T));
  *size = sizeof(T);
  return ONI_STATUS_OK;
}

template <class T>
bool take(const void* data, int size, T& value) {
  if (data == nullptr || size != static_cast<int>(sizeof(T))) return false;
  std::memcpy(&value, data, sizeof(T));
  return true;
}

// One sensor's stream. Its settings are read by the device's thread while the application may
// change them, hence the mutex.
class VirtualStream final : public oni::driver::StreamBase {
 public:
  VirtualStream(OniSensorType type, const Playback& playback, std::vector<OniVideoMode> modes)
      : type_(type),
        playback_(playback),
        modes_(std::move(modes)),
        mode_(modes_.front()),
        mirrored_(playback.options.mirrored) {}

  OniStatus start() override {
    started_ = true;
    return ONI_STATUS_OK;
  }
  void stop() override { started_ = false; }
  [[nodiscard]] bool started() const { return started_; }

  OniBool isPropertySupported(int id) override {
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE:
      case ONI_STREAM_PROPERTY_MIRRORING:
      case ONI_STREAM_PROPERTY_STRIDE:
      case ONI_STREAM_PROPERTY_CROPPING: return TRUE;
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
      case ONI_STREAM_PROPERTY_VERTICAL_FOV:
      case kIntrinsicsProperty: return playback_.options.fov ? TRUE : FALSE;
      case XN_STREAM_PROPERTY_ZERO_PLANE_DISTANCE:
      case XN_STREAM_PROPERTY_ZERO_PLANE_PIXEL_SIZE: return zero_plane() ? TRUE : FALSE;
      case ONI_STREAM_PROPERTY_MAX_VALUE:
      case ONI_STREAM_PROPERTY_MIN_VALUE: return type_ == ONI_SENSOR_DEPTH;
      default: return FALSE;
    }
  }

  OniStatus getProperty(int id, void* data, int* size) override {
    const std::lock_guard lock(mutex_);
    const auto& k = playback_.intrinsics;
    if (!isPropertySupported(id)) return ONI_STATUS_NOT_SUPPORTED;
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE: return put(data, size, mode_);
      // PS1080's types: an unsigned 64-bit integer of millimetres, a double of millimetres.
      case XN_STREAM_PROPERTY_ZERO_PLANE_DISTANCE:
        return put(data, size, static_cast<std::uint64_t>(std::llround(*playback_.options.zpd_mm)));
      case XN_STREAM_PROPERTY_ZERO_PLANE_PIXEL_SIZE: return put(data, size, *playback_.options.zpps_mm);
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
        return put(data, size, static_cast<float>(2.0 * std::atan(width_of(playback_) / (2.0 * k.fx))));
      case ONI_STREAM_PROPERTY_VERTICAL_FOV:
        return put(data, size, static_cast<float>(2.0 * std::atan(height_of(playback_) / (2.0 * k.fy))));
      case ONI_STREAM_PROPERTY_MIRRORING: return put(data, size, static_cast<OniBool>(mirrored_));
      case ONI_STREAM_PROPERTY_STRIDE: return put(data, size, mode_.resolutionX * bytes_per_pixel());
      case ONI_STREAM_PROPERTY_CROPPING: return put(data, size, OniCropping{});
      case ONI_STREAM_PROPERTY_MAX_VALUE: return put(data, size, 65535);
      case ONI_STREAM_PROPERTY_MIN_VALUE: return put(data, size, 0);
      case kIntrinsicsProperty: return put(data, size, scaled(k));
      default: return ONI_STATUS_NOT_SUPPORTED;
    }
  }

  OniStatus setProperty(int id, const void* data, int size) override {
    const std::lock_guard lock(mutex_);
    if (id == ONI_STREAM_PROPERTY_MIRRORING) {
      OniBool on = FALSE;
      if (!take(data, size, on)) return ONI_STATUS_BAD_PARAMETER;
      if (playback_.options.mirrored) return on ? ONI_STATUS_OK : ONI_STATUS_NOT_SUPPORTED;  // fixed
      mirrored_ = on != FALSE;
      return ONI_STATUS_OK;
    }
    if (id == ONI_STREAM_PROPERTY_VIDEO_MODE) {
      OniVideoMode wanted{};
      if (!take(data, size, wanted)) return ONI_STATUS_BAD_PARAMETER;
      for (const auto& m : modes_)
        if (m.pixelFormat == wanted.pixelFormat && m.resolutionX == wanted.resolutionX &&
            m.resolutionY == wanted.resolutionY && m.fps == wanted.fps) {
          mode_ = m;
          return ONI_STATUS_OK;
        }
      return ONI_STATUS_NOT_SUPPORTED;  // only the recording's own size and rate
    }
    if (id == ONI_STREAM_PROPERTY_CROPPING) {  // accepted when it asks for none
      OniCropping c{};
      return take(data, size, c) && c.enabled == 0 ? ONI_STATUS_OK : ONI_STATUS_NOT_SUPPORTED;
    }
    return ONI_STATUS_NOT_SUPPORTED;
  }

  // What OpenNI's Recorder writes when it attaches the stream: PS1080's zero-plane values, as the
  // PS1080 driver announces them.
  void notifyAllProperties() override {
    if (!zero_plane()) return;
    const auto zpd = static_cast<std::uint64_t>(std::llround(*playback_.options.zpd_mm));
    const double zpps = *playback_.options.zpps_mm;
    raisePropertyChanged(XN_STREAM_PROPERTY_ZERO_PLANE_DISTANCE, &zpd, sizeof(zpd));
    raisePropertyChanged(XN_STREAM_PROPERTY_ZERO_PLANE_PIXEL_SIZE, &zpps, sizeof(zpps));
  }

  // The sizes OpenNI allocates frames of: the largest mode, so that a mode change never needs more.
  int getRequiredFrameSize() override {
    return std::max(width_of(playback_) * height_of(playback_),
                    colour_width_of(playback_) * colour_height_of(playback_)) *
           3;
  }

  /// Sends frame `index` (1-based, as devices number them) of `image` (BGR or raw depth in units of
  /// `depth_scale` per metre), when started.
  void emit(const cv::Mat& image, double depth_scale, int index, std::uint64_t timestamp_us) {
    if (!started_) return;
    OniFrame* frame = getServices().acquireFrame();
    if (frame == nullptr) return;
    {
      const std::lock_guard lock(mutex_);
      frame->sensorType = type_;
      frame->videoMode = mode_;
      frame->width = mode_.resolutionX;
      frame->height = mode_.resolutionY;
      frame->stride = mode_.resolutionX * bytes_per_pixel();
      frame->dataSize = frame->stride * frame->height;
      frame->croppingEnabled = FALSE;
      frame->cropOriginX = frame->cropOriginY = 0;
      frame->frameIndex = index;
      frame->timestamp = timestamp_us;
      convert(image, depth_scale, *frame);
    }
    raiseNewFrame(frame);
    getServices().releaseFrame(frame);
  }

 private:
  // The folder's camera at this stream's size (colour_size scales colour; pixel centres stay).
  [[nodiscard]] StreamIntrinsics scaled(StreamIntrinsics k) const {
    const double sx = static_cast<double>(mode_.resolutionX) / width_of(playback_),
                 sy = static_cast<double>(mode_.resolutionY) / height_of(playback_);
    if (sx == 1.0 && sy == 1.0) return k;
    k.fx *= sx;
    k.fy *= sy;
    k.cx = (k.cx + 0.5) * sx - 0.5;
    k.cy = (k.cy + 0.5) * sy - 0.5;
    return k;
  }
  [[nodiscard]] bool zero_plane() const { return type_ == ONI_SENSOR_DEPTH && playback_.options.zpd_mm.has_value(); }
  [[nodiscard]] int bytes_per_pixel() const { return mode_.pixelFormat == ONI_PIXEL_FORMAT_RGB888 ? 3 : 2; }

  void convert(const cv::Mat& image, double depth_scale, OniFrame& frame) const {
    if (type_ == ONI_SENSOR_COLOR) {
      cv::Mat rgb(frame.height, frame.width, CV_8UC3, frame.data, static_cast<std::size_t>(frame.stride));
      if (image.size() == rgb.size()) {
        cv::cvtColor(image, rgb, cv::COLOR_BGR2RGB);
      } else {  // colour_size: a camera's smaller colour mode
        cv::Mat scaled;
        cv::resize(image, scaled, rgb.size(), 0, 0, cv::INTER_AREA);
        cv::cvtColor(scaled, rgb, cv::COLOR_BGR2RGB);
      }
      if (mirrored_) cv::flip(rgb, rgb, 1);
      return;
    }
    // Depth in OpenNI's unit; a value that unit cannot hold is no measurement (0), not a wrong one.
    const double per_metre = mode_.pixelFormat == ONI_PIXEL_FORMAT_DEPTH_100_UM ? 10000.0 : 1000.0;
    const double factor = per_metre / depth_scale;
    cv::Mat out(frame.height, frame.width, CV_16UC1, frame.data, static_cast<std::size_t>(frame.stride));
    for (int y = 0; y < out.rows; ++y) {
      const auto* in = image.ptr<std::uint16_t>(y);
      auto* row = out.ptr<std::uint16_t>(y);
      for (int x = 0; x < out.cols; ++x) {
        const double v = std::round(in[x] * factor);
        row[mirrored_ ? out.cols - 1 - x : x] = v <= 65535.0 ? static_cast<std::uint16_t>(v) : 0;
      }
    }
  }

  const OniSensorType type_;
  const Playback& playback_;
  const std::vector<OniVideoMode> modes_;
  std::atomic<bool> started_{false};
  mutable std::mutex mutex_;
  OniVideoMode mode_;
  bool mirrored_ = false;
};

class VirtualDriver;

// One connection of the device: its sensors, streams and the thread that plays frames into them.
class VirtualDevice final : public oni::driver::DeviceBase {
 public:
  VirtualDevice(VirtualDriver& driver, std::shared_ptr<Playback> playback);
  ~VirtualDevice() override {
    thread_.request_stop();
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
  }
  VirtualDevice(const VirtualDevice&) = delete;
  VirtualDevice& operator=(const VirtualDevice&) = delete;

  OniStatus getSensorInfoList(OniSensorInfo** infos, int* count) override {
    *infos = sensors_.data();
    *count = static_cast<int>(sensors_.size());
    return ONI_STATUS_OK;
  }

  oni::driver::StreamBase* createStream(OniSensorType type) override {
    const std::lock_guard lock(streams_mutex_);
    auto& slot = type == ONI_SENSOR_DEPTH ? depth_ : type == ONI_SENSOR_COLOR ? colour_ : none_;
    if (&slot == &none_ || slot) return nullptr;  // one stream per sensor
    slot = std::make_unique<VirtualStream>(type, *playback_, type == ONI_SENSOR_DEPTH ? depth_modes_ : colour_modes_);
    return slot.get();
  }

  void destroyStream(oni::driver::StreamBase* stream) override {
    const std::lock_guard lock(streams_mutex_);
    for (auto* slot : {&depth_, &colour_})
      if (slot->get() == stream) slot->reset();
  }

  OniBool isPropertySupported(int id) override {
    return id == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION || id == kPacedProperty ? TRUE : FALSE;
  }

  OniStatus getProperty(int id, void* data, int* size) override {
    const std::lock_guard lock(mutex_);
    if (id == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION) return put(data, size, registration_);
    if (id == kPacedProperty) return put(data, size, paced_ ? 1 : 0);
    return ONI_STATUS_NOT_SUPPORTED;
  }

  OniStatus setProperty(int id, const void* data, int size) override {
    const std::lock_guard lock(mutex_);
    if (id == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION) {
      // TUM depth is registered already: both modes give the same images.
      return take(data, size, registration_) ? ONI_STATUS_OK : ONI_STATUS_BAD_PARAMETER;
    }
    if (id == kPacedProperty) {
      int paced = 1;
      if (!take(data, size, paced)) return ONI_STATUS_BAD_PARAMETER;
      paced_ = paced != 0;
      wake_.notify_all();
      return ONI_STATUS_OK;
    }
    return ONI_STATUS_NOT_SUPPORTED;
  }

  OniBool isImageRegistrationModeSupported(OniImageRegistrationMode mode) override {
    return mode == ONI_IMAGE_REGISTRATION_OFF || mode == ONI_IMAGE_REGISTRATION_DEPTH_TO_COLOR ? TRUE : FALSE;
  }

  // OpenNI calls this while an application waits with no frame pending: unpaced, the next frame is
  // played here, on the application's thread, so that one wait is one frame and none can overtake
  // a frame not yet read.
  OniStatus tryManualTrigger() override {
    {
      const std::lock_guard lock(mutex_);
      if (paced_) return ONI_STATUS_OK;
    }
    if (streaming()) step(nullptr);
    return ONI_STATUS_OK;
  }

 private:
  [[nodiscard]] bool streaming() {
    const std::lock_guard lock(streams_mutex_);
    return (depth_ && depth_->started()) || (colour_ && colour_->started());
  }
  void play(const std::stop_token& stop);
  bool step(const std::stop_token* stop);
  bool wait_until_due(const std::stop_token& stop, double timestamp);
  void send(const core::RgbdFrame& frame, std::size_t index);

  VirtualDriver& driver_;
  const std::shared_ptr<Playback> playback_;
  std::vector<OniVideoMode> depth_modes_, colour_modes_;
  std::vector<OniSensorInfo> sensors_;
  std::mutex mutex_;  // the settings and the thread's wake-up conditions
  std::condition_variable_any wake_;
  std::mutex streams_mutex_;  // the streams, while the thread sends into them
  std::unique_ptr<VirtualStream> depth_, colour_, none_;
  OniImageRegistrationMode registration_ = ONI_IMAGE_REGISTRATION_OFF;
  bool paced_ = true;
  std::mutex play_mutex_;              // one frame played at a time, by the thread or a trigger
  std::atomic<bool> finished_{false};  // this connection has ended or been unplugged
  std::optional<std::pair<Clock::time_point, double>> anchor_;  // paced: first frame's time and stamp
  std::jthread thread_;                                         // last: started once everything it reads exists
};

// The driver: the one object of this plug-in that OpenNI keeps (ONI_EXPORT_DRIVER), with the
// playbacks of every URI opened in this process and the timers of unplugged devices.
class VirtualDriver final : public oni::driver::DriverBase {
 public:
  explicit VirtualDriver(OniDriverServices* services) : DriverBase(services) {}
  ~VirtualDriver() override { shutdown(); }
  VirtualDriver(const VirtualDriver&) = delete;
  VirtualDriver& operator=(const VirtualDriver&) = delete;

  OniStatus tryDevice(const char* uri) override {
    if (uri == nullptr || !std::string_view(uri).starts_with(kScheme)) return ONI_STATUS_ERROR;
    const auto playback = find_or_open(uri);
    if (!playback) return ONI_STATUS_ERROR;
    {
      const std::lock_guard lock(mutex_);
      if (playback->unplugged) {
        getServices().errorLoggerAppend("%s is unplugged", uri);
        return ONI_STATUS_ERROR;
      }
    }
    deviceConnected(&playback->info);
    return ONI_STATUS_OK;
  }

  oni::driver::DeviceBase* deviceOpen(const char* uri, const char* /*mode*/) override {
    std::shared_ptr<Playback> playback;
    {
      const std::lock_guard lock(mutex_);
      if (const auto it = playbacks_.find(uri); it != playbacks_.end() && !it->second->unplugged) playback = it->second;
    }
    if (!playback) return nullptr;
    return new VirtualDevice(*this, playback);
  }

  void deviceClose(oni::driver::DeviceBase* device) override { delete device; }

  void shutdown() override {
    std::vector<std::jthread> timers;
    {
      const std::lock_guard lock(mutex_);
      timers.swap(replug_timers_);
    }
    for (auto& t : timers) t.request_stop();
    timers.clear();  // joins
  }

  // Frames of every stream of one device carry one index: OpenNI pairs them by it.
  void* enableFrameSync(oni::driver::StreamBase** /*streams*/, int /*count*/) override { return this; }
  void disableFrameSync(void* /*group*/) override {}

  /// What the device's thread plays next: a frame, the end, or nothing (it has just been unplugged).
  enum class Next { kFrame, kEnd, kUnplugged };
  Next take_next(Playback& p, std::size_t& index) {
    {
      const std::lock_guard lock(mutex_);
      if (p.unplugged) return Next::kUnplugged;
      const bool unplug = p.options.unplug_after && !p.unplug_done && p.played >= *p.options.unplug_after;
      if (!unplug) {
        if (p.next >= p.sequence.size()) return Next::kEnd;
        index = p.next++;
        ++p.played;
        return Next::kFrame;
      }
      p.unplug_done = p.unplugged = true;
      if (p.options.replug_after_s) schedule_replug(p);
    }
    deviceDisconnected(&p.info);  // outside the lock: OpenNI's handlers take their own
    return Next::kUnplugged;
  }

  void ended(const Playback& p) { deviceStateChanged(&p.info, ONI_DEVICE_STATE_EOF); }

 private:
  std::shared_ptr<Playback> find_or_open(const char* uri) {
    {
      const std::lock_guard lock(mutex_);
      if (const auto it = playbacks_.find(uri); it != playbacks_.end()) return it->second;
    }
    std::string why;
    auto parsed = parse_uri(uri, &why);
    if (!parsed) {
      getServices().errorLoggerAppend("%s: %s", uri, why.c_str());
      return nullptr;
    }
    if (std::strlen(uri) >= ONI_MAX_STR) {
      getServices().errorLoggerAppend("%s: longer than OpenNI's %d characters", uri, ONI_MAX_STR - 1);
      return nullptr;
    }
    try {
      auto sequence = io::TumSequence::open(parsed->dir);
      auto playback = std::make_shared<Playback>(uri, std::move(*parsed), std::move(sequence));
      const std::lock_guard lock(mutex_);
      return playbacks_.try_emplace(uri, std::move(playback)).first->second;
    } catch (const std::exception& e) {  // io::InputError, or intrinsics TumSequence refuses
      getServices().errorLoggerAppend("%s: %s", uri, e.what());
      return nullptr;
    }
  }

  // Called with mutex_ held. The timer reconnects the device unless the driver shuts down first.
  void schedule_replug(Playback& p) {
    const auto wait = std::chrono::duration<double>(*p.options.replug_after_s);
    replug_timers_.emplace_back([this, &p, wait](const std::stop_token& stop) {
      std::mutex m;
      std::unique_lock lock(m);
      std::condition_variable_any cv;
      cv.wait_for(lock, stop, wait, [] { return false; });
      if (stop.stop_requested()) return;
      {
        const std::lock_guard guard(mutex_);
        p.unplugged = false;
      }
      deviceConnected(&p.info);
    });
  }

  std::mutex mutex_;
  std::map<std::string, std::shared_ptr<Playback>, std::less<>> playbacks_;
  std::vector<std::jthread> replug_timers_;
};

VirtualDevice::VirtualDevice(VirtualDriver& driver, std::shared_ptr<Playback> playback)
    : driver_(driver), playback_(std::move(playback)) {
  const int w = width_of(*playback_), h = height_of(*playback_), fps = playback_->fps;
  depth_modes_ = {{ONI_PIXEL_FORMAT_DEPTH_1_MM, w, h, fps}, {ONI_PIXEL_FORMAT_DEPTH_100_UM, w, h, fps}};
  colour_modes_ = {{ONI_PIXEL_FORMAT_RGB888, colour_width_of(*playback_), colour_height_of(*playback_), fps}};
  sensors_ = {{ONI_SENSOR_DEPTH, static_cast<int>(depth_modes_.size()), depth_modes_.data()},
              {ONI_SENSOR_COLOR, static_cast<int>(colour_modes_.size()), colour_modes_.data()}};
  thread_ = std::jthread([this](const std::stop_token& stop) { play(stop); });
}

// Paced, the thread plays frame after frame at the recorded rate; unpaced, it only waits.
void VirtualDevice::play(const std::stop_token& stop) {
  while (!stop.stop_requested() && !finished_) {
    {
      std::unique_lock lock(mutex_);
      if (!wake_.wait_for(lock, stop, std::chrono::milliseconds(20), [this] { return paced_ && streaming(); }))
        continue;
    }
    step(&stop);
  }
}

// Plays the next frame (paced, when it is due: `stop` ends the wait); false once this connection
// has nothing more to play: the end of the folder, or the unplug.
bool VirtualDevice::step(const std::stop_token* stop) {
  const std::lock_guard playing(play_mutex_);
  if (finished_) return false;
  std::size_t index = 0;
  const auto next = driver_.take_next(*playback_, index);
  if (next != VirtualDriver::Next::kFrame) {
    finished_ = true;
    if (next == VirtualDriver::Next::kEnd) driver_.ended(*playback_);
    return false;
  }
  core::RgbdFrame frame;
  try {
    frame = playback_->sequence.read(index);
  } catch (const std::exception&) {  // an unreadable image: a camera would drop that frame too
    return true;
  }
  const cv::Size size(width_of(*playback_), height_of(*playback_));
  if (frame.bgr.size() != size || frame.depth.size() != size || frame.depth.type() != CV_16UC1)
    return true;  // likewise
  if (stop != nullptr && !wait_until_due(*stop, frame.timestamp)) return false;
  send(frame, index);
  return true;
}

// Paced: the first frame is due at once, every later one at its recorded offset from it.
bool VirtualDevice::wait_until_due(const std::stop_token& stop, double timestamp) {
  std::unique_lock lock(mutex_);
  if (!paced_) return true;
  if (!anchor_) anchor_ = {Clock::now(), timestamp};
  const auto due = anchor_->first + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(timestamp - anchor_->second));
  wake_.wait_until(lock, stop, due, [this] { return !paced_; });  // unpaced from now: at once
  return !stop.stop_requested();
}

void VirtualDevice::send(const core::RgbdFrame& frame, std::size_t index) {
  const auto us = [](double seconds) { return static_cast<std::uint64_t>(std::llround(seconds * 1e6)); };
  const int number = static_cast<int>(index) + 1;
  {
    const std::lock_guard streams(streams_mutex_);
    if (depth_) depth_->emit(frame.depth, frame.intrinsics.depth_scale, number, us(frame.depth_timestamp));
    if (colour_) colour_->emit(frame.bgr, frame.intrinsics.depth_scale, number, us(frame.timestamp));
  }
}

}  // namespace
}  // namespace cvo::drivers::virtual_device

using cvo_virtual_driver = cvo::drivers::virtual_device::VirtualDriver;
ONI_EXPORT_DRIVER(cvo_virtual_driver)
