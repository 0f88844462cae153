#include "backend_probe.hpp"

#include <chrono>
#include <csignal>
#include <fstream>
#include <stdexcept>

#include "cvo_lcm/map_correction_t.hpp"
#include "cvo_lcm/map_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "libcvo/core/units.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/private_network.hpp"

namespace cvo::bench {
namespace fs = std::filesystem;

BackendProbe::BackendProbe(const fs::path& backendd, const fs::path& dir, const std::vector<std::string>& settings)
    : store_(dir / "map.store"), out_(testing::kPrivateLcmUrl), in_(testing::kPrivateLcmUrl) {
  if (!out_.good() || !in_.good()) throw std::runtime_error("map_scale: LCM is not available on the private bus");
  in_.subscribe("CVO_(MAP_CORRECTION|MAP|STATUS|KEYFRAME|POSE)", &BackendProbe::handle, this);
  receiver_ = std::thread([this] { receive(); });
  std::vector<std::string> args{"--lcm-url", testing::kPrivateLcmUrl, "--store", store_.string()};
  for (const auto& s : settings) args.insert(args.end(), {"--set", s});
  auto daemon = std::make_unique<testing::DaemonProcess>(backendd, args, dir / "backendd.txt");
  // What is sent before it listens is lost: its first CVO_STATUS says it does.
  std::unique_lock lock(mutex_);
  daemon_ = std::move(daemon);
  if (!changed_.wait_for(lock, std::chrono::seconds(60), [&] { return listening_; }))
    throw std::runtime_error("map_scale: cvo-backendd sent no CVO_STATUS within 60 s (see " +
                             (dir / "backendd.txt").string() + ")");
}

BackendProbe::~BackendProbe() {
  {
    const std::lock_guard lock(mutex_);
    stop_ = true;
  }
  receiver_.join();
}

void BackendProbe::receive() {
  while (true) {
    {
      const std::lock_guard lock(mutex_);
      if (stop_) return;
    }
    in_.handleTimeout(100);
  }
}

void BackendProbe::handle(const ::lcm::ReceiveBuffer* buffer, const std::string& channel) {
  const std::lock_guard lock(mutex_);
  const auto bytes = static_cast<std::size_t>(buffer->data_size);
  if (channel == "CVO_STATUS") {
    cvo_lcm::status_t status;
    if (status.decode(buffer->data, 0, buffer->data_size) > 0 && daemon_ && status.pid == daemon_->pid()) {
      listening_ = true;
      published_.waiting = status.queue_depth;
      changed_.notify_all();
    }
    return;
  }
  if (channel == "CVO_KEYFRAME" || channel == "CVO_POSE") {
    ++(channel == "CVO_POSE" ? published_.tracker_poses : published_.tracker_keyframes);
    return;
  }
  if (channel == "CVO_MAP") {
    ++published_.maps;
    published_.map_bytes += bytes;
    cvo_lcm::map_t map;
    if (map.decode(buffer->data, 0, buffer->data_size) > 0)
      published_.last_map_keyframes = static_cast<std::size_t>(map.num_keyframes);
    return;
  }
  ++published_.corrections;
  published_.correction_bytes += bytes;
  cvo_lcm::map_correction_t c;
  if (c.decode(buffer->data, 0, buffer->data_size) <= 0) return;
  auto& held = held_[c.session.session];
  held = std::max(held, static_cast<std::size_t>(c.session.keyframes));
  changed_.notify_all();
}

void BackendProbe::publish_graph(const std::vector<std::uint8_t>& bytes) {
  out_.publish("CVO_LOCAL_GRAPH", bytes.data(), static_cast<unsigned>(bytes.size()));
}

std::optional<double> BackendProbe::publish_keyframe(std::int64_t session, std::size_t keyframes_held,
                                                     const std::vector<std::uint8_t>& bytes, double timeout_s) {
  const auto start = core::SteadyClock::now();
  out_.publish("CVO_KEYFRAME", bytes.data(), static_cast<unsigned>(bytes.size()));
  std::unique_lock lock(mutex_);
  const bool came = changed_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                                      [&] { return held_[session] >= keyframes_held; });
  if (!came) return std::nullopt;
  return core::ms_since(start);
}

Snapshot BackendProbe::snapshot() const {
  Snapshot s;
  {
    const std::lock_guard lock(mutex_);
    s.published = published_;
  }
  s.rss_bytes = resident_bytes(daemon_->pid());
  std::error_code ec;
  const auto size = fs::file_size(store_, ec);
  s.store_bytes = ec ? 0 : static_cast<std::size_t>(size);
  return s;
}

int BackendProbe::stop() {
  daemon_->signal(SIGTERM);
  return daemon_->wait_for(std::chrono::seconds(120)).value_or(-9);
}

std::size_t resident_bytes(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmRSS:", 0) == 0) return static_cast<std::size_t>(std::stoull(line.substr(6))) * 1024;
  return 0;
}

}  // namespace cvo::bench
