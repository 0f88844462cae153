#include "daemon/trackerd/trackerd.hpp"

#include <chrono>
#include <string>
#include <thread>
#include <utility>

#include <lcm/lcm-cpp.hpp>

#include "daemon/common/realtime.hpp"
#include "daemon/common/signals.hpp"
#include "daemon/common/supervise.hpp"
#include "daemon/trackerd/publishing.hpp"
#include "daemon/trackerd/spool.hpp"
#include "daemon/trackerd/tracking.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"

namespace cvo::daemon::trackerd {

using namespace std::chrono_literals;

Trackerd::Trackerd(config::Config config) : Trackerd(std::move(config), SourceFactory{}) {}

Trackerd::Trackerd(config::Config config, SourceFactory open_source) : open_source_(std::move(open_source)) {
  const auto& t = config.trackerd;
  if (t.source.find(':') == std::string::npos)
    throw io::InputError("trackerd.source", "'" + t.source + "': expected tum:DIR, lcm:URL, openni2:URI or v4l2:DEV");
  if (!lcm::parse_colour_encoding(t.keyframe_colour_encoding))
    throw io::InputError("trackerd.keyframe_colour_encoding",
                         "'" + t.keyframe_colour_encoding + "': expected raw, jpeg or png");
  // A spool that cannot be written would keep nothing across a crash, each write failing later:
  // refused at the start, as any unusable setting.
  if (!t.spool.empty() && t.spool != "none")
    if (const auto why = Spool::unusable(t.spool); !why.empty()) throw io::InputError("trackerd.spool", why);
  ::lcm::LCM probe(t.lcm_url);  // the publisher opens its own; a bad URL should fail at start-up
  if (!probe.good()) throw io::InputError("trackerd.lcm_url", "cannot open LCM provider '" + t.lcm_url + "'");
  shared_ = std::make_unique<Shared>(std::move(config));  // reads the key file
  if (!open_source_) open_source_ = configured_source(shared_->config, shared_->bus);
}

Trackerd::~Trackerd() = default;

int Trackerd::run() {
  Shared& s = *shared_;
  const auto& t = s.config.trackerd;
  s.notes.note("session " + core::session_name(s.session));
  s.notes.note(s.bus.describe());
  s.notes.note("source " + t.source + ", publishing on " + t.lcm_url + (t.deterministic ? " (deterministic)" : ""));
  if (t.lock_memory)
    if (const auto why = lock_all_memory(); !why.empty())
      s.notes.note("warning: " + why + "; running without locked memory");

  Acquisition acquisition(s, open_source_);
  Tracking tracking(s);
  Publishing publishing(s);
  std::thread acquire([&] { acquisition.run(); });
  std::thread track([&] { tracking.run(); });
  std::thread publish([&] { publishing.run(); });
  s.systemd.ready();

  const Heartbeat* const beats[] = {&s.track_heartbeat, &s.publish_heartbeat};
  // The source ended (exit-on-eof) or could not be opened, or the publisher is done.
  const auto ended = [&] { return s.publisher_done || (s.tracker_done && !s.stop); };
  if (const auto signal = supervise(s.systemd, {beats, 5s}, ended))
    s.notes.note(std::string("stopping on ") + signal_name(*signal));
  s.stop = true;
  s.ring.close();
  acquire.join();
  track.join();
  publish.join();
  closing_note();
  return s.source_failed ? 1 : 0;
}

void Trackerd::closing_note() {
  Shared& s = *shared_;
  const auto& c = s.counters;
  s.notes.note("tracked " + std::to_string(c.frames_tracked.load()) + " frames: " + std::to_string(c.keyframes.load()) +
               " keyframes, " + std::to_string(c.failed_frames.load()) + " failed, " +
               std::to_string(s.ring.dropped()) + " dropped by the ring, " +
               std::to_string(c.source_lost_frames.load()) +
               " missing from the source; tracking-thread allocations after warm-up: " +
               std::to_string(c.allocations_after_warmup.load()));
}

}  // namespace cvo::daemon::trackerd
