#pragma once
// The one small interface every frame source implements: timestamped colour + registered depth
// with intrinsics (core::RgbdFrame), read one at a time by the daemon's acquisition thread.
// Sources are opened by the spec that names them (open_source.hpp).
//
// A read never throws on bad data: the result says what happened, so the caller can count it
// and go on. Only open_source() throws, on a spec it cannot understand or a source that cannot be
// opened (the caller retries with back-off for devices that may come back).
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "libcvo/core/bad_kind.hpp"
#include "libcvo/core/camera.hpp"
#include "libcvo/core/depth_sensor.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/io/input_error.hpp"

namespace cvo::auth {
class KeyRing;  // libcvo/auth/key.hpp
}

namespace cvo::drivers {

enum class ReadStatus {
  kFrame,         // `frame` holds the next frame
  kTimeout,       // nothing within the timeout; try again
  kEndOfStream,   // a finite source (folder, log file, .oni) has no more frames
  kBadInput,      // one message or frame was unusable and skipped (see bad_input, message)
  kDisconnected,  // the device or stream went away; close this source and open it again
};

struct ReadResult {
  ReadStatus status = ReadStatus::kTimeout;
  // Why a message or frame was refused: the shared list of refusal kinds (libcvo/core/bad_kind.hpp),
  // CVO_STATUS's bad_messages indices, so the daemon counts them straight into CVO_STATUS.
  core::BadKind bad_input = core::BadKind::kContent;  // when status == kBadInput
  std::string message;                                // why, for kBadInput and kDisconnected
};

struct SourceOptions {
  bool realtime = true;  // tum: pace frames at their recorded rate (else as fast as possible)
  std::string lcm_channel = "CVO_RGBD";
  // Intrinsics for sources that do not carry them (v4l2; TUM folders without camera.yaml and
  // with an unrecognised name). nullopt: the source's own, or its best guess.
  std::optional<core::Intrinsics> intrinsics;
  // A depth node that is a separate sensor (v4l2): its depth is registered to the colour camera
  // (depth_registration.hpp) before the frame leaves the driver. nullopt: depth is registered.
  std::optional<core::DepthSensor> depth_sensor;
  int width = 640, height = 480, fps = 30;  // requested mode of devices (openni2, v4l2)
  // lcm: the deployment's keys (auth.key_file, libcvo/auth): every message is verified on its raw
  // bytes before it is decoded (a refusal is kBadInput kAuth or kReplay; a file:// log is checked
  // for authenticity only, it is a recording). null: an open bus.
  std::shared_ptr<const auth::KeyRing> bus_keys;
  std::int64_t bus_max_age_us = 30'000'000;  // auth.max_age_s
};

/// The spec did not name a known source, or the source could not be opened (missing folder,
/// no device, bad LCM URL). The message says which and why.
class SourceError : public io::InputError {
 public:
  using io::InputError::InputError;
  /// The same error (file, line, message) as a SourceError, e.g. a TUM folder's InputError.
  explicit SourceError(const io::InputError& error) : io::InputError(error) {}
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  /// Waits up to `timeout` for the next frame and writes it into `frame`, reusing its image
  /// buffers when the size and type match (so a steady stream does not allocate images anew).
  virtual ReadResult read(core::RgbdFrame& frame, std::chrono::milliseconds timeout) = 0;

  /// One line for logs and CVO_STATUS, e.g. "tum:/data/fr1_rpy (475 frames, realtime)".
  [[nodiscard]] virtual std::string describe() const = 0;

  /// Frames this source knows were lost before read() could return them (gaps in the sender's
  /// frame numbers, frames a device overwrote, unpaired colour or depth images), so that no loss
  /// goes uncounted. Refused input is not included: read() reports each one as kBadInput.
  [[nodiscard]] virtual std::uint64_t lost_frames() const { return 0; }
};

/// "frame", "timeout", "end of stream", "bad input", "disconnected".
const char* to_string(ReadStatus status);
/// Of a core::BadKind: "too short", "fingerprint", "body", "version", "content", "image size", ...
using core::to_string;

}  // namespace cvo::drivers
