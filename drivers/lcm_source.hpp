#pragma once
// lcm:URL — cvo_lcm::rgbd_frame_t messages on channel options.lcm_channel from an LCM provider:
// live ("udpm://239.255.76.67:7667?ttl=0"; "" is LCM's default) or a log that LCM's own file
// provider replays ("file:///data/run.lcm?speed=0" as fast as possible, speed=1 at the recorded
// rate). The channel is matched as LCM does, as a regular expression.
//
// Each message on the channel is one read() result: kFrame, or kBadInput with the check that
// refused it (with options.bus_keys, libcvo/auth first: auth, replay; then lcm::decode: too short,
// fingerprint, body, version; lcm::from_message: content).
// Events on other channels are skipped. At the end of a file:// log, kEndOfStream; when a live
// provider fails, kDisconnected. Frames that never reached us (LCM's receive queue was full, the
// network lost them) show as gaps in the sender's frame_index and are counted in lost_frames().
// Each frame's images are newly decoded (lcm::from_message), not written into the caller's buffers.
#include <memory>
#include <string_view>

#include "drivers/frame_source.hpp"

namespace cvo::drivers {

/// Throws SourceError when LCM cannot open the URL (bad URL, missing or empty log file).
std::unique_ptr<FrameSource> open_lcm(std::string_view url, const SourceOptions& options);

}  // namespace cvo::drivers
