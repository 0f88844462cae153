#pragma once
// The real cvo-backendd, driven as its trackers drive it and watched as an operator watches it:
// started with a store of its own on the private bus (udpm, ttl=0, inside in-private-netns), fed
// CVO_LOCAL_GRAPH and CVO_KEYFRAME messages in closed loop (the next keyframe goes out once the back
// end's update for the last one came back, so its queue never hides its cost), and measured
// from outside, once its first CVO_STATUS said it listens: a keyframe's latency is from its publication to the first
// CVO_MAP_CORRECTION of its session that counts it (map_session_t.keyframes); every CVO_MAP_CORRECTION and CVO_MAP it
// publishes is counted with its bytes (and a tracker's CVO_KEYFRAME and CVO_POSE, where one runs); its resident memory
// is the kernel's (VmRSS), its store's size the file's.
#include <sys/types.h>

#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

namespace cvo::testing {
class DaemonProcess;
}

namespace cvo::bench {

struct Published {
  std::size_t corrections = 0, correction_bytes = 0;     // CVO_MAP_CORRECTION
  std::size_t maps = 0, map_bytes = 0;                   // CVO_MAP
  std::size_t last_map_keyframes = 0;                    // keyframes in the newest CVO_MAP
  std::int32_t waiting = 0;                              // records waiting: its newest CVO_STATUS queue_depth
  std::size_t tracker_keyframes = 0, tracker_poses = 0;  // CVO_KEYFRAME, CVO_POSE heard from a tracker
};

struct Snapshot {
  Published published;
  std::size_t rss_bytes = 0, store_bytes = 0;
};

class BackendProbe {
 public:
  /// cvo-backendd with its store in `dir`, `settings` ("key=value") passed as --set.
  BackendProbe(const std::filesystem::path& backendd, const std::filesystem::path& dir,
               const std::vector<std::string>& settings);
  ~BackendProbe();
  BackendProbe(const BackendProbe&) = delete;
  BackendProbe& operator=(const BackendProbe&) = delete;

  void publish_graph(const std::vector<std::uint8_t>& bytes);
  /// Publishes the keyframe and waits for its update: the latency in ms, nullopt when none came
  /// within `timeout_s` (the back end counted `keyframes_held` of the session by then).
  std::optional<double> publish_keyframe(std::int64_t session, std::size_t keyframes_held,
                                         const std::vector<std::uint8_t>& bytes, double timeout_s = 60);
  [[nodiscard]] Snapshot snapshot() const;
  /// SIGTERM, the exit status once it stopped (its final CVO_MAP is in snapshot() then).
  int stop();

 private:
  void receive();
  void handle(const ::lcm::ReceiveBuffer* buffer, const std::string& channel);

  std::filesystem::path store_;
  std::unique_ptr<testing::DaemonProcess> daemon_;
  ::lcm::LCM out_, in_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::int64_t, std::size_t> held_;  // by session: the most keyframes a correction counted
  Published published_;
  bool stop_ = false, listening_ = false;
  std::thread receiver_;
};

/// VmRSS of a process, in bytes (0 when it is gone).
std::size_t resident_bytes(pid_t pid);

}  // namespace cvo::bench
