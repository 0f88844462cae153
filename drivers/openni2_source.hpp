#pragma once
// openni2:URI — an OpenNI2 device (PrimeSense, Asus Xtion, Orbbec, Kinect through its driver) or
// an .oni recording, or the project's virtual device.
//   URI: "" or "any" the first device; a device URI as OpenNI lists it; a path ending in ".oni";
//   "cvo-virtual:DIR[?unplug_after=N&replug_after_s=S]" the project's virtual device playing the
//   TUM folder DIR (drivers/openni2_virtual/virtual_device.hpp). The programs load OpenNI2 through
//   the project's runtime directory, whose drivers repository holds the system's drivers and that
//   one (drivers/openni2_virtual/CMakeLists.txt).
//
// Opening sets up a depth stream (PIXEL_FORMAT_DEPTH_1_MM; the virtual device's DEPTH_100_UM, exact
// for TUM's units) and a colour stream (RGB888) of options.width x height at options.fps (a recording
// keeps its own modes), mirroring off (a stream that stays mirrored, a recording made so, is flipped
// back), depth registered to colour when the device can, depth/colour frame sync on. Frames have
// colour's size: depth of another size is registered with options.depth_sensor when given, else
// (registered by the device) scaled to it by nearest neighbour. Intrinsics: openni2_camera_model.hpp
// (the camera file, the device's own model, fields of view, PS1080 zero-plane values, a known
// camera's published focal length), their source in describe(); depth_scale is the depth
// format's, 1000 or 10000.
//
// A file (oni_file.hpp) is checked before OpenNI sees it: a missing, unreadable, foreign or empty
// file is a SourceError saying so (never a USB hint); a recording never closed or cut off plays
// its whole frames from a repaired temporary copy.
//
// options.realtime false: a recording plays frame by frame as read (speed -1), and the virtual
// device likewise (its kPacedProperty), so that a slow consumer loses none; else both play at the
// recorded rate.
//
// read() waits (OpenNI::waitForAnyStream, up to the timeout) until it holds a new depth and a new
// colour frame, and returns them as one frame: colour as BGR, depth in the stream's unit. Timestamps are
// the device clock moved onto the system clock at the first frame. A device error or a
// disconnection is kDisconnected; the end of a recording (played once) or a device state of
// DEVICE_STATE_EOF (the virtual device at the end of its folder) is kEndOfStream.
// OpenNI keeps only the newest frame of a stream, so a consumer that falls behind loses frames;
// they are counted (from OpenNI's frame indices) in lost_frames().
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "drivers/frame_source.hpp"

namespace cvo::drivers {

/// Throws SourceError, with OpenNI's own explanation, when no device (or file) opens or a stream
/// cannot be set up.
std::unique_ptr<FrameSource> open_openni2(std::string_view uri, const SourceOptions& options);

/// open_openni2(uri, options) whose streams OpenNI's own Recorder also writes to the .oni file `oni`
/// from the moment it returns until the source is destroyed: every frame the device sends, read or
/// not (with options.realtime false the virtual device sends one per read). Throws SourceError as
/// open_openni2 does, and naming the file when the recording cannot be made.
std::unique_ptr<FrameSource> open_openni2_recording(std::string_view uri, const std::filesystem::path& oni,
                                                    const SourceOptions& options);

/// Initialises OpenNI (once per process: its drivers then watch USB for devices until exit) and
/// returns its version, e.g. "2.2.0.33". Throws SourceError when it cannot initialise (no drivers).
std::string openni2_version();

}  // namespace cvo::drivers
