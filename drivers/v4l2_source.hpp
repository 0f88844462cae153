#pragma once
// v4l2:COLOUR,DEPTH — two V4L2 capture nodes of one RGB-D camera (e.g. a RealSense through the
// uvcvideo driver: "v4l2:/dev/video4,/dev/video0"), streamed with mmap buffers.
//
// Colour is YUYV, else MJPEG; depth is Z16 (V4L2_PIX_FMT_Z16). Both at the intrinsics' size and
// options.fps. V4L2 says nothing about the optics, so options.intrinsics are required; their
// depth_scale is the Z16 unit (1000: millimetres). Depth must already be registered to colour
// (the camera does it, or the intrinsics are the depth camera's and colour is aligned to it).
//
// read() waits (poll) up to the timeout for frames of both nodes and pairs them by capture time:
// a colour and a depth frame within half a frame period are one frame; an unpaired older frame is
// dropped and counted in lost_frames(), as are frames the driver skipped (buffer sequence gaps).
// Timestamps are the buffers' (monotonic) capture times moved onto the system clock. A frame the
// driver marks corrupt, or one that does not convert, is kBadInput / kContent; a device that goes
// away (ENODEV, poll errors) is kDisconnected, once the frames dequeued before it are paired (a
// camera unplugged between DQBUF and QBUF leaves a whole frame).
#include <memory>
#include <string_view>

#include "drivers/frame_source.hpp"

namespace cvo::drivers {

/// Throws SourceError: "v4l2 needs intrinsics (--camera ...)" without options.intrinsics; naming the
/// node when it is missing, not a streaming capture device, or has no suitable format.
std::unique_ptr<FrameSource> open_v4l2(std::string_view nodes, const SourceOptions& options);

}  // namespace cvo::drivers
