#pragma once
// The source a spec names, the `--source` contract of cvo-trackerd:
//   tum:DIR          a TUM RGB-D folder, at the recorded rate or as fast as possible
//   lcm:URL          CVO_RGBD messages from an LCM provider: live (udpm://...) or a log (file://...)
//   openni2:URI      an OpenNI2 device URI, "" / "any" for the first device, or an .oni recording
//   v4l2:COLOUR,DEPTH  V4L2 device nodes (mmap streaming; YUYV/MJPEG colour, Z16 depth)
#include <memory>
#include <string_view>

#include "drivers/frame_source.hpp"

namespace cvo::drivers {

/// Opens the source a spec names. Throws SourceError on a spec it cannot understand or a source
/// that cannot be opened.
std::unique_ptr<FrameSource> open_source(std::string_view spec, const SourceOptions& options = {});

/// Whether the spec names a device that may come and go (openni2: cameras and the virtual device,
/// v4l2: nodes), to be re-opened with back-off; false for finite sources (folders, logs, .oni
/// files), whose failure to open is final.
bool names_device(std::string_view spec);

}  // namespace cvo::drivers
