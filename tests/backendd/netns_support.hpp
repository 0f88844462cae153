#pragma once
// What the back-end tests over UDP multicast share: the daemons started the way a robot starts
// them, and a capture of what is published (an LCM log for cvo-log, and the decoded messages the
// tests wait on and check). Only ever used inside tests/support/in-private-netns.
#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/keyframe_chunk_t.hpp"
#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/map_correction_t.hpp"
#include "cvo_lcm/map_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "libcvo/lcm/chunks.hpp"
#include "libcvo/lcm/decode.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/private_network.hpp"

namespace cvo::testing {

using KeyframeName = std::pair<std::int64_t, std::int64_t>;  // (session, id)

inline constexpr const char* kUrl = kPrivateLcmUrl;

/// `map` holds every keyframe of `names`: each session's entry counts at least its names
/// (map_session_t.keyframes: what the back end holds of it, keyframes merged into earlier ones
/// included, which the map's keyframe list leaves out: slam/mapper.hpp, revisits), and the names
/// not in the keyframe list are at most those merged: what the entry counts beyond the list.
inline bool map_holds(const cvo_lcm::map_t& map, const std::set<KeyframeName>& names) {
  std::map<std::int64_t, std::size_t> named, listed, in_list;
  for (const auto& n : names) ++named[n.first];
  for (const auto& k : map.keyframes) {
    ++in_list[k.session];
    listed[k.session] += names.count({k.session, k.id});
  }
  for (const auto& [session, count] : named) {
    const auto entry = std::find_if(map.sessions.begin(), map.sessions.end(),
                                    [&](const cvo_lcm::map_session_t& e) { return e.session == session; });
    if (entry == map.sessions.end()) return false;
    const auto held = static_cast<std::size_t>(std::max(0, entry->keyframes));
    if (held < count || held < in_list[session] || held - in_list[session] < count - listed[session]) return false;
  }
  return true;
}

struct Captured {
  std::optional<cvo_lcm::map_t> map;                     // the last CVO_MAP
  std::vector<cvo_lcm::status_t> backend_statuses;       // cvo-backendd's CVO_STATUS, in order
  std::set<KeyframeName> keyframes;                      // every CVO_KEYFRAME seen, whole or a slice of it
  std::map<std::int64_t, std::int64_t> last_frame;       // CVO_POSE: each session's newest frame index
  std::map<std::int64_t, std::int64_t> newest_keyframe;  // CVO_POSE: each session's newest keyframe id
  std::map<std::int64_t, std::int64_t> acknowledged;     // CVO_MAP_CORRECTION: each session's, the highest
  // The same, of corrections whose entry counts no keyframe: sent before the mapper applied any
  // record of the session.
  std::map<std::int64_t, std::int64_t> acknowledged_unmapped;
  // CVO_POSE: each session's states as they changed (pose_t STATE_*), sessions in the order seen.
  std::vector<std::pair<std::int64_t, std::vector<std::int8_t>>> state_changes;

  /// The last map holds every keyframe of `names` (cvo::testing::map_holds).
  [[nodiscard]] bool map_holds(const std::set<KeyframeName>& names) const {
    return map ? testing::map_holds(*map, names) : names.empty();
  }
  [[nodiscard]] std::set<KeyframeName> keyframes_of(std::int64_t session) const {
    std::set<KeyframeName> out;
    for (const auto& k : keyframes)
      if (k.first == session) out.insert(k);
    return out;
  }
  /// A CVO_STATUS of the back end with this pid (in this state) came.
  [[nodiscard]] bool status_from(int pid, std::optional<std::int8_t> state = std::nullopt) const {
    for (const auto& s : backend_statuses)
      if (s.pid == pid && (!state || s.state == *state)) return true;
    return false;
  }
};

/// Receives every cvo-slam channel in a thread of its own from construction on; CVO_MAP and
/// CVO_STATUS also go to an LCM log (what cvo-log reads). Waiting on it is waiting for what the
/// daemons said, not for time to pass.
class LcmCapture {
 public:
  explicit LcmCapture(const std::filesystem::path& log, const std::string& url = kUrl)
      : log_(log.string(), "w"), lcm_(url) {
    lcm_.subscribe("CVO_.*", &LcmCapture::handle, this)->setQueueCapacity(10000);  // bursts of slices
    thread_ = std::thread([this] {
      pthread_setname_np(pthread_self(), "lcm-capture");
      while (!stop_) lcm_.handleTimeout(50);
    });
  }
  ~LcmCapture() {
    stop_ = true;
    thread_.join();
  }
  LcmCapture(const LcmCapture&) = delete;
  LcmCapture& operator=(const LcmCapture&) = delete;

  [[nodiscard]] bool good() { return log_.good() && lcm_.good(); }

  /// True once `condition` holds for what was captured; false when `limit` passed first.
  bool wait_until(const std::function<bool(const Captured&)>& condition, std::chrono::seconds limit) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, limit, [&] { return condition(captured_); });
  }
  Captured snapshot() {
    const std::lock_guard lock(mutex_);
    return captured_;
  }

 private:
  void handle(const ::lcm::ReceiveBuffer* buffer, const std::string& channel) {
    const auto size = static_cast<int>(buffer->data_size);
    {
      const std::lock_guard lock(mutex_);
      if (channel == "CVO_MAP" || channel == "CVO_STATUS") {
        ::lcm::LogEvent event{0, buffer->recv_utime, channel, size, buffer->data};
        log_.writeEvent(&event);
      }
      if (channel == "CVO_MAP") {
        if (auto m = cvo::lcm::decode<cvo_lcm::map_t>(buffer->data, size, nullptr)) captured_.map = std::move(*m);
      } else if (channel == "CVO_STATUS") {
        auto s = cvo::lcm::decode<cvo_lcm::status_t>(buffer->data, size, nullptr);
        if (s && s->process == "cvo-backendd") captured_.backend_statuses.push_back(std::move(*s));
      } else if (channel == "CVO_MAP_CORRECTION") {
        if (const auto m = cvo::lcm::decode<cvo_lcm::map_correction_t>(buffer->data, size, nullptr)) {
          auto& acknowledged = captured_.acknowledged[m->session.session];
          acknowledged = std::max(acknowledged, m->acknowledged);
          if (m->session.keyframes == 0) {
            auto& unmapped = captured_.acknowledged_unmapped[m->session.session];
            unmapped = std::max(unmapped, m->acknowledged);
          }
        }
      } else if (channel == "CVO_KEYFRAME") {
        if (const auto k = cvo::lcm::decode<cvo_lcm::keyframe_t>(buffer->data, size, nullptr))
          captured_.keyframes.emplace(k->session, k->id);
      } else if (channel == "CVO_KEYFRAME_CHUNK") {  // sent once every slice of it was (a killed tracker's may not be)
        const auto c = cvo::lcm::decode<cvo_lcm::keyframe_chunk_t>(buffer->data, size, nullptr);
        if (c && c->message == cvo_lcm::keyframe_chunk_t::KEYFRAME &&
            slices_.add(*c).outcome == cvo::lcm::ChunkAssembly::Added::Outcome::kComplete)
          captured_.keyframes.emplace(c->session, c->id);
      } else if (channel == "CVO_POSE") {
        if (const auto p = cvo::lcm::decode<cvo_lcm::pose_t>(buffer->data, size, nullptr)) {
          auto& last = captured_.last_frame[p->session];
          last = std::max(last, p->frame_index);
          const auto newest = captured_.newest_keyframe.try_emplace(p->session, p->keyframe_id).first;
          newest->second = std::max(newest->second, p->keyframe_id);
          auto& changes = captured_.state_changes;
          if (changes.empty() || changes.back().first != p->session) changes.push_back({p->session, {}});
          if (changes.back().second.empty() || changes.back().second.back() != p->state)
            changes.back().second.push_back(p->state);
        }
      }
    }
    changed_.notify_all();
  }

  ::lcm::LogFile log_;
  ::lcm::LCM lcm_;
  std::mutex mutex_;
  std::condition_variable changed_;
  Captured captured_;
  cvo::lcm::ChunkAssembly slices_;  // under mutex_
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

inline std::unique_ptr<DaemonProcess> start_backendd(const std::filesystem::path& store,
                                                     const std::filesystem::path& stderr_file,
                                                     const std::vector<std::string>& settings = {}) {
  std::vector<std::string> args{"--lcm-url", kUrl, "--store", store.string()};
  for (const auto& s : settings) args.insert(args.end(), {"--set", s});
  return std::make_unique<DaemonProcess>(std::filesystem::path(CVO_TOOLS_DIR) / "cvo-backendd", args, stderr_file);
}

/// cvo-trackerd on a TUM folder at its recorded rate (30 Hz), every frame tracked (deterministic);
/// with `exit_at_end` it exits 0 after the last frame, else it stays up as a live one would;
/// `settings` are --set KEY=VALUE assignments.
inline DaemonProcess start_trackerd(const std::filesystem::path& folder, const std::filesystem::path& stderr_file,
                                    bool exit_at_end, const std::vector<std::string>& settings = {}) {
  std::vector<std::string> args{"--source",
                                "tum:" + folder.string(),
                                "--lcm-url",
                                kUrl,
                                "--deterministic",
                                "--set",
                                "trackerd.realtime_priority=0",
                                "--set",
                                "trackerd.lock_memory=false"};
  if (exit_at_end) args.emplace_back("--exit-on-eof");
  for (const auto& s : settings) args.insert(args.end(), {"--set", s});
  return DaemonProcess(std::filesystem::path(CVO_TOOLS_DIR) / "cvo-trackerd", args, stderr_file);
}

/// SIGTERM, then the exit status (nullopt when it did not exit within `limit`).
inline std::optional<int> stop(DaemonProcess& daemon, std::chrono::seconds limit) {
  daemon.signal(SIGTERM);
  return daemon.wait_for(limit);
}

/// The number after "key": in a one-object JSON text (cvo-eval --json); NaN when absent.
inline double json_number(const std::string& json, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + key + "\": ([-0-9.eE+]+)"))) return std::nan("");
  return std::stod(m[1]);
}

}  // namespace cvo::testing
