#pragma once
// openni2:URI — an OpenNI2 device (PrimeSense, Asus Xtion, Orbbec, Kinect through its driver) or
// an .oni recording.
//   URI: "" or "any" the first device; a device URI as OpenNI lists it; a path ending in ".oni".
//
// Opening sets up a depth stream (PIXEL_FORMAT_DEPTH_1_MM) and a colour stream (RGB888) of
// options.width x height at options.fps (a recording keeps its own mode), mirroring off, depth
// registered to colour when the device can, depth/colour frame sync on. Intrinsics:
// options.intrinsics, else from the colour stream's fields of view, fx = w / 2 / tan(hfov / 2)
// with the principal point at the image centre (OpenNI's own convention); depth_scale 1000.
//
// read() waits (OpenNI::waitForAnyStream, up to the timeout) until it holds a new depth and a new
// colour frame, and returns them as one frame: colour as BGR, depth in millimetres. Timestamps are
// the device clock moved onto the system clock at the first frame. A device error is
// kDisconnected; the end of a recording (played once, at its recorded rate) is kEndOfStream.
// OpenNI keeps only the newest frame of a stream, so a consumer that falls behind loses frames;
// they are counted (from OpenNI's frame indices) in lost_frames().
#include <memory>
#include <string>
#include <string_view>

#include "drivers/frame_source.hpp"

namespace cvo::drivers {

/// Throws SourceError, with OpenNI's own explanation, when no device (or file) opens or a stream
/// cannot be set up.
std::unique_ptr<FrameSource> open_openni2(std::string_view uri, const SourceOptions& options);

/// Initialises OpenNI (once per process: its drivers then watch USB for devices until exit) and
/// returns its version, e.g. "2.2.0.33". Throws SourceError when it cannot initialise (no drivers).
std::string openni2_version();

}  // namespace cvo::drivers
