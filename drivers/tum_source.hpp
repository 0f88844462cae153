#pragma once
// tum:DIR — a TUM RGB-D folder (io::TumSequence) as a frame source.
//
// With options.realtime each frame is returned at its recorded time: the clock is anchored at the
// first frame (steady clock), so slow reads do not accumulate drift and a consumer that falls
// behind gets the following frames at once. Otherwise frames come as fast as they are read.
// A frame whose images cannot be used is kBadInput / kContent (the message names the file) and the
// next read goes on with the following frame; after the last frame, kEndOfStream. Each frame's
// images are newly decoded (io::TumSequence), not written into the caller's buffers.
#include <filesystem>
#include <memory>

#include "drivers/frame_source.hpp"

namespace cvo::drivers {

/// Intrinsics: options.intrinsics, else the folder's camera.yaml, else the preset its name implies.
/// Throws SourceError on a missing or malformed folder (the message names the file).
std::unique_ptr<FrameSource> open_tum(const std::filesystem::path& dir, const SourceOptions& options);

}  // namespace cvo::drivers
