#pragma once
// cvo-backendd's wiring: two named threads around libcvo's loop closure and SLAM back end.
//
//   cvo-receive   LCM CVO_KEYFRAME / CVO_LOCAL_GRAPH -> decoded and checked -> appended to the
//                 keyframe store (durable before anything else happens) -> work queue
//   cvo-backend   work queue -> slam::Backend (local graphs) and loop_closure::LoopDetector
//                 (keyframes) -> keyframe-graph optimisation after new loops -> CVO_MAP;
//                 CVO_STATUS once a period
//
// At start-up the store is read back and every record goes through the same path, so a restart
// resumes with every keyframe received before. On SIGTERM/SIGINT: the queue is drained, a final
// global optimisation runs, the final CVO_MAP is published, exit 0.
//
// Node ids of the back end and the loop detector are frame indices (the tracker's); CVO_MAP
// names keyframes by the tracker's keyframe ids, as cvo-trackerd's correction expects.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "daemon/backendd/keyframe_store.hpp"
#include "daemon/common/systemd_notify.hpp"
#include "libcvo/config/config.hpp"

namespace cvo::daemon::backendd {

/// The vocabulary file a config names: "default" is loop_closure::default_vocabulary_file();
/// anything else a path.
std::filesystem::path resolve_vocabulary(const std::string& setting);

class Backendd {
 public:
  /// Opens the store (recovering its records) and the LCM provider, loads the vocabulary; throws
  /// io::InputError naming what is wrong.
  explicit Backendd(config::Config config);
  ~Backendd();
  Backendd(const Backendd&) = delete;
  Backendd& operator=(const Backendd&) = delete;

  /// Runs until SIGTERM/SIGINT; returns the exit status. block_stop_signals() must have been
  /// called before.
  int run();

 private:
  struct Work;
  void receive_loop();
  void work_loop();
  void note(const std::string& detail);

  config::Config config_;
  SystemdNotifier systemd_;
  std::unique_ptr<KeyframeStore> store_;
  std::vector<StoredRecord> recovered_;
  std::unique_ptr<Work> work_;  // the back end, the detector and what they know; cvo-backend only

  std::mutex queue_mutex_;
  std::condition_variable queue_ready_;
  std::deque<StoredRecord> queue_;
  std::atomic<bool> stop_{false}, receiver_done_{false};
  std::atomic<std::int64_t> bad_messages_[5]{};
  std::atomic<std::int64_t> receive_heartbeat_ns_{0}, work_heartbeat_ns_{0};

  std::mutex detail_mutex_;
  std::string detail_;
};

}  // namespace cvo::daemon::backendd
