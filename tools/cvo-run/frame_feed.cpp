#include "frame_feed.hpp"

#include <chrono>
#include <string_view>

#include "drivers/open_source.hpp"

namespace cvo::tools {
namespace {

using namespace std::chrono_literals;
constexpr auto kQuiet = 10s;  // a source that sends nothing this long has ended without saying so

}  // namespace

bool is_source_spec(const std::string& sequence) {
  for (const std::string_view scheme : {"tum:", "lcm:", "openni2:", "v4l2:"})
    if (sequence.starts_with(scheme)) return true;
  return false;
}

FrameFeed FrameFeed::open(const std::string& sequence, const io::TumOptions& options) {
  FrameFeed feed;
  feed.max_frames_ = options.max_frames;
  if (!is_source_spec(sequence)) {
    if (!std::filesystem::is_directory(sequence)) throw io::InputError(sequence, "no such folder");
    feed.folder_ = io::TumSequence::open(sequence, options);
    return feed;
  }
  drivers::SourceOptions source_options;
  source_options.realtime = false;  // every frame, as fast as it is tracked
  source_options.intrinsics = options.intrinsics;
  feed.source_ = drivers::open_source(sequence, source_options);
  auto first = feed.next_from_source();
  if (first.kind != Item::Kind::kFrame)
    throw drivers::SourceError(sequence, "no frame" + (first.error.empty() ? std::string() : ": " + first.error));
  feed.intrinsics_ = first.frame->intrinsics;
  feed.ahead_ = std::move(first.frame);
  return feed;
}

const core::Intrinsics& FrameFeed::intrinsics() const { return folder_ ? folder_->intrinsics() : intrinsics_; }

const core::Trajectory& FrameFeed::groundtruth() const { return folder_ ? folder_->groundtruth() : no_groundtruth_; }

std::size_t FrameFeed::expected_frames() const { return folder_ ? folder_->size() : max_frames_; }

std::string FrameFeed::describe() const { return source_ ? source_->describe() : std::string(); }

FrameFeed::Item FrameFeed::next() {
  if (folder_) {
    const std::size_t index = folder_->position();
    try {
      auto frame = folder_->next();
      if (!frame) return {};
      return {Item::Kind::kFrame, std::move(frame), index, 0, {}};
    } catch (const io::FrameError& e) {  // the folder has moved past the frame
      return {Item::Kind::kBad, std::nullopt, e.frame_index(), folder_->files()[index].timestamp, e.what()};
    }
  }
  if (max_frames_ > 0 && read_ >= max_frames_) return {};
  ++read_;
  if (ahead_) {
    Item item{Item::Kind::kFrame, std::move(ahead_), 0, 0, {}};
    ahead_.reset();
    return item;
  }
  auto item = next_from_source();
  item.index = read_ - 1;
  return item;
}

// Reads on through timeouts; a bad frame is reported and the next one follows; a device that goes
// away ends the run (offline there is no waiting for it).
FrameFeed::Item FrameFeed::next_from_source() {
  core::RgbdFrame frame;
  auto quiet_since = std::chrono::steady_clock::now();
  for (;;) {
    const auto r = source_->read(frame, 100ms);
    switch (r.status) {
      case drivers::ReadStatus::kFrame: {
        const double stamp = frame.timestamp;
        return {Item::Kind::kFrame, std::move(frame), 0, stamp, {}};
      }
      case drivers::ReadStatus::kBadInput: return {Item::Kind::kBad, std::nullopt, 0, 0, r.message};
      case drivers::ReadStatus::kEndOfStream: return {};
      case drivers::ReadStatus::kDisconnected: return {Item::Kind::kEnd, std::nullopt, 0, 0, r.message};
      case drivers::ReadStatus::kTimeout:
        if (std::chrono::steady_clock::now() - quiet_since > kQuiet)
          return {Item::Kind::kEnd, std::nullopt, 0, 0, "nothing for 10 s"};
        break;
    }
  }
}

}  // namespace cvo::tools
