#include "daemon/trackerd/acquisition.hpp"

#include <chrono>
#include <exception>
#include <thread>

#include "daemon/common/realtime.hpp"
#include "drivers/reconnecting_source.hpp"
#include "libcvo/io/intrinsics_file.hpp"

namespace cvo::daemon::trackerd {
namespace {

using namespace std::chrono_literals;

// Intrinsics for the sources that carry none (v4l2): the configured camera, and its depth sensor
// when depth is separate. The others bring their own (TUM folder, CVO_RGBD message, OpenNI2 stream).
drivers::SourceOptions source_options(const config::Config& config, const BusAuth& bus) {
  drivers::SourceOptions options;
  options.realtime = config.trackerd.paced;
  options.bus_keys = bus.keys();  // an lcm: source verifies every CVO_RGBD
  options.bus_max_age_us = bus.max_age_us();
  // v4l2 needs the camera; an OpenNI2 camera or recording says its own, and a camera the user sets
  // (any but the default) overrides what it says (drivers/openni2_camera_model.hpp).
  const bool openni2_given = config.trackerd.source.starts_with("openni2:") && config.camera != config::Config{}.camera;
  if (config.trackerd.source.starts_with("v4l2:") || openni2_given) {
    const io::CameraFile camera = io::load_camera_file(config.camera);
    options.intrinsics = camera.colour;
    options.depth_sensor = camera.depth_sensor;
  }
  return options;
}

}  // namespace

SourceFactory configured_source(const config::Config& config, const BusAuth& bus) {
  return [spec = config.trackerd.source,
          options = source_options(config, bus)]() -> std::unique_ptr<drivers::FrameSource> {
    if (drivers::names_device(spec)) return std::make_unique<drivers::ReconnectingSource>(spec, options);
    return drivers::open_source(spec, options);
  };
}

void Acquisition::run() {
  name_this_thread("cvo-acquire");
  std::unique_ptr<drivers::FrameSource> source;
  try {
    source = open_source_();
  } catch (const std::exception& e) {
    shared_.notes.note(std::string("cannot open the frame source: ") + e.what());
    // A folder, log or .oni that is wrong now stays wrong (exit 1); devices are retried instead.
    shared_.source_failed = true;
    shared_.ring.close();
    return;
  }
  shared_.notes.note("reading " + source->describe());
  shared_.counters.source_connected = true;
  while (!shared_.stop) {
    RingSlot* slot = shared_.ring.begin_write();
    if (slot == nullptr) return;  // closed
    if (read_into(*source, *slot)) {
      shared_.ring.commit_write();
      continue;
    }
    shared_.ring.abort_write();
  }
}

// One read: true when the slot holds a frame to commit. A timeout, bad input or a disconnection
// gives the slot back; the end of a finite source ends the thread's work (see ended()).
bool Acquisition::read_into(drivers::FrameSource& source, RingSlot& slot) {
  const auto result = source.read(slot.frame, 100ms);
  shared_.counters.source_lost_frames = static_cast<std::int64_t>(source.lost_frames());
  switch (result.status) {
    case drivers::ReadStatus::kFrame:
      // A device opens lazily: what it is (size, intrinsics and their source) is said once, here.
      if (!described_) {
        described_ = true;
        shared_.notes.note("first frame from " + source.describe());
      }
      if (!connected_) {
        connected_ = true;
        ++connection_;
        next_index_ = 0;
        shared_.counters.source_connected = true;
        shared_.notes.note("frames again from " + source.describe());
      }
      slot.received = Clock::now();
      slot.frame.index = static_cast<std::uint64_t>(next_index_++);
      slot.connection = connection_;
      return true;
    case drivers::ReadStatus::kTimeout: return false;
    case drivers::ReadStatus::kBadInput:
      shared_.count_bad(static_cast<int>(result.bad_input), "skipped bad input", result.message);
      return false;
    case drivers::ReadStatus::kDisconnected: disconnected(result.message); return false;
    case drivers::ReadStatus::kEndOfStream: ended(source); return false;
  }
  return false;
}

void Acquisition::disconnected(const std::string& message) {
  if (!connected_) return;
  connected_ = false;
  shared_.counters.source_connected = false;
  ++shared_.counters.source_gaps;
  shared_.notes.note("source lost: " + message + "; re-opening with back-off");
}

// With exit_on_eof the ring closes (the tracker finishes what waits, and the daemon ends); else
// the daemon stays up, reporting, until it is stopped.
void Acquisition::ended(const drivers::FrameSource& source) {
  shared_.notes.note("end of " + source.describe());
  if (shared_.config.trackerd.exit_on_eof) {
    shared_.ring.close();
    return;
  }
  while (!shared_.stop) std::this_thread::sleep_for(50ms);
}

}  // namespace cvo::daemon::trackerd
