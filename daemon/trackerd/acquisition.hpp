#pragma once
// cvo-acquire: the frame source (drivers/) into the FrameRing. A device that goes away is re-opened
// with back-off by its ReconnectingSource; each time frames come again is a new connection
// (RingSlot::connection), from which the tracker starts a new session. What the source refuses
// is counted by kind; a source that cannot be opened at all is fatal (Shared::source_failed).
#include <functional>
#include <memory>

#include "daemon/trackerd/shared.hpp"
#include "drivers/frame_source.hpp"

namespace cvo::daemon::trackerd {

using SourceFactory = std::function<std::unique_ptr<drivers::FrameSource>()>;

/// The source trackerd.source names (devices re-opened with back-off). Throws io::InputError for a
/// camera file that cannot be used, at start-up rather than in a thread.
SourceFactory configured_source(const config::Config& config, const BusAuth& bus);

class Acquisition {
 public:
  Acquisition(Shared& shared, SourceFactory open_source) : shared_(shared), open_source_(std::move(open_source)) {}
  void run();  // the thread's body: until Shared::stop, or the source's end

 private:
  bool read_into(drivers::FrameSource& source, RingSlot& slot);
  void disconnected(const std::string& message);
  void ended(const drivers::FrameSource& source);

  Shared& shared_;
  SourceFactory open_source_;
  // Frame indices count from 0 in each connection; a new connection is a new session.
  std::int64_t next_index_ = 0;
  std::uint64_t connection_ = 0;
  bool connected_ = true;
  bool described_ = false;  // the source's description noted at its first frame
};

}  // namespace cvo::daemon::trackerd
