// Both daemons on an authenticated bus (auth.key_file, libcvo/auth), over real LCM UDP multicast,
// attacked by a process of the test that does not hold the key (plain LCM, no cvo-slam signer):
//   - a CVO_MAP copied from the back end's and changed (its session's correction moved 0.5 m,
//     revision + 1000), sent as copied, and signed with another deployment's key, and the real map
//     sent again unchanged: no map pose moves, the refusals are counted as BAD_AUTH and BAD_REPLAY
//     in the tracker's CVO_STATUS, and the genuine maps are still applied; 50 keyframe requests
//     (unsigned) for the tracker's session re-send nothing;
//   - a tracker with another deployment's key, and one on an open bus, are refused whole by the
//     back end (every message counted, none stored or mapped);
//   - rotation: a tracker holding {old, new} and a back end holding {old} interoperate, and so do
//     {new, old} and {old, new}.
// The frames come signed too: tum2lcm --key-file records the clip, lcm-logplayer plays it to the
// tracker's lcm: source. Runs only inside tests/support/in-private-netns (CVO_PRIVATE_NETNS=1).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/keyframe_chunk_t.hpp"
#include "cvo_lcm/keyframe_request_t.hpp"
#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/map_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "libcvo/auth/authenticator.hpp"
#include "libcvo/auth/key.hpp"
#include "libcvo/lcm/chunks.hpp"
#include "libcvo/lcm/decode.hpp"
#include "tests/backendd/netns_support.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/private_network.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/slowdown.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::DaemonProcess;
using cvo::testing::scaled;
using cvo::testing::which;
using S = cvo_lcm::status_t;

constexpr const char* kUrl = cvo::testing::kPrivateLcmUrl;
const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";

// What the daemons said, raw CVO_MAPs included (an attacker copies them).
struct Heard {
  std::vector<std::vector<std::uint8_t>> raw_maps;
  std::vector<cvo_lcm::pose_t> poses;
  std::map<std::string, cvo_lcm::status_t> last_status;  // by process
  std::set<std::pair<std::int64_t, std::int64_t>> keyframes;
  std::optional<cvo_lcm::map_t> map;
  std::vector<std::uint8_t> newest_keyframe;  // the bytes of the newest CVO_KEYFRAME heard

  [[nodiscard]] bool map_holds_every_keyframe() const {
    return map && !keyframes.empty() && testing::map_holds(*map, keyframes);
  }
};

class Listener {
 public:
  Listener() : lcm_(kUrl) {
    lcm_.subscribe("CVO_.*", &Listener::handle, this)->setQueueCapacity(10000);  // bursts of slices
    thread_ = std::thread([this] {
      while (!stop_) lcm_.handleTimeout(50);
    });
  }
  ~Listener() {
    stop_ = true;
    thread_.join();
  }
  Listener(const Listener&) = delete;
  Listener& operator=(const Listener&) = delete;

  bool wait_until(const std::function<bool(const Heard&)>& condition, std::chrono::milliseconds limit) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, limit, [&] { return condition(heard_); });
  }
  Heard snapshot() {
    const std::lock_guard lock(mutex_);
    return heard_;
  }

 private:
  void handle(const ::lcm::ReceiveBuffer* b, const std::string& channel) {
    const auto size = static_cast<int>(b->data_size);
    const auto* data = static_cast<const std::uint8_t*>(b->data);
    {
      const std::lock_guard lock(mutex_);
      if (channel == "CVO_MAP") {
        heard_.raw_maps.emplace_back(data, data + size);
        if (auto m = lcm::decode<cvo_lcm::map_t>(data, size, nullptr)) heard_.map = std::move(*m);
      } else if (channel == "CVO_POSE") {
        if (auto p = lcm::decode<cvo_lcm::pose_t>(data, size, nullptr)) heard_.poses.push_back(*p);
      } else if (channel == "CVO_STATUS") {
        if (auto s = lcm::decode<cvo_lcm::status_t>(data, size, nullptr)) heard_.last_status[s->process] = *s;
      } else if (channel == "CVO_KEYFRAME") {
        // Signed ones only (a forgery below is not): what the tracker really made.
        auto k = lcm::decode<cvo_lcm::keyframe_t>(data, size, nullptr);
        if (k && k->auth.sender != 0) {
          heard_.keyframes.emplace(k->session, k->id);
          heard_.newest_keyframe.assign(data, data + size);
        }
      } else if (channel == "CVO_KEYFRAME_CHUNK") {  // the same, in slices (the tracker's default)
        auto c = lcm::decode<cvo_lcm::keyframe_chunk_t>(data, size, nullptr);
        if (c && c->auth.sender != 0 && c->message == cvo_lcm::keyframe_chunk_t::KEYFRAME) {
          if (auto added = slices_.add(*c); added.outcome == lcm::ChunkAssembly::Added::Outcome::kComplete) {
            heard_.keyframes.emplace(c->session, c->id);
            heard_.newest_keyframe = std::move(added.message);
          }
        }
      }
    }
    changed_.notify_all();
  }

  ::lcm::LCM lcm_;
  std::mutex mutex_;
  lcm::ChunkAssembly slices_;  // under mutex_
  std::condition_variable changed_;
  Heard heard_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

fs::path make_keys(const fs::path& file, std::size_t count) {
  std::vector<auth::Key> keys;
  for (std::size_t i = 0; i < count; ++i) keys.push_back(auth::Key::generate());
  auth::create_key_file(file, auth::KeyRing(std::move(keys)));
  return file;
}

// A key file of the same keys as `from`, in the other order (the rotation's next step).
fs::path swapped(const fs::path& from, const fs::path& file) {
  auto keys = auth::read_key_file(from).release();
  std::reverse(keys.begin(), keys.end());
  auth::create_key_file(file, auth::KeyRing(std::move(keys)));
  return file;
}

std::string key_setting(const std::optional<fs::path>& key) {
  return "auth.key_file=" + (key ? key->string() : std::string("none"));
}

std::unique_ptr<DaemonProcess> start_tracker(const std::string& source, const std::optional<fs::path>& key,
                                             const fs::path& stderr_file, bool exit_at_end) {
  std::vector<std::string> args{"--source",
                                source,
                                "--lcm-url",
                                kUrl,
                                "--deterministic",
                                "--set",
                                "trackerd.realtime_priority=0",
                                "--set",
                                "trackerd.lock_memory=false"};
  args.insert(args.end(), {"--set", key_setting(key)});
  if (exit_at_end) args.emplace_back("--exit-on-eof");
  return std::make_unique<DaemonProcess>(fs::path(CVO_TOOLS_DIR) / "cvo-trackerd", args, stderr_file);
}

std::unique_ptr<DaemonProcess> start_backend(const fs::path& dir, const std::optional<fs::path>& key,
                                             const std::string& name) {
  return cvo::testing::start_backendd(dir / (name + ".store"), dir / (name + ".backendd.txt"), {key_setting(key)});
}

std::int64_t tracker_session(const Heard& h) {
  const auto s = h.last_status.find("cvo-trackerd");
  return s == h.last_status.end() ? 0 : s->second.session;
}

// The last CVO_MAP that places `session`, raw, or empty.
std::vector<std::uint8_t> placing_map(const Heard& h, std::int64_t session) {
  for (auto it = h.raw_maps.rbegin(); it != h.raw_maps.rend(); ++it) {
    const auto m = lcm::decode<cvo_lcm::map_t>(it->data(), static_cast<int>(it->size()), nullptr);
    if (!m) continue;
    for (const auto& s : m->sessions)
      if (s.session == session && s.placed) return *it;
  }
  return {};
}

// The real map changed as an attacker would: the session's correction 0.5 m along x, a revision far
// ahead (so that it would win over every genuine map). Its trailer is the real map's, now wrong.
std::vector<std::uint8_t> forged_from(const std::vector<std::uint8_t>& real, std::int64_t session) {
  auto m = lcm::decode<cvo_lcm::map_t>(real.data(), static_cast<int>(real.size()), nullptr).value();
  m.revision += 1000;
  for (auto& s : m.sessions)
    if (s.session == session) s.correction.position[0] += 0.5;
  return lcm::encode(m);  // auth copied as it was
}

double largest_map_shift_m(const std::vector<cvo_lcm::pose_t>& poses) {
  double largest = 0;
  for (const auto& p : poses) {
    if (!p.has_map_pose) continue;
    const double dx = p.map_pose.position[0] - p.odom_pose.position[0];
    const double dy = p.map_pose.position[1] - p.odom_pose.position[1];
    const double dz = p.map_pose.position[2] - p.odom_pose.position[2];
    largest = std::max(largest, std::sqrt(dx * dx + dy * dy + dz * dz));
  }
  return largest;
}

class AuthenticatedBus : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
  }
  cvo::test::TempDir dir_{"cvo_auth_bus"};
};

TEST_F(AuthenticatedBus, ForgedAndReplayedMapsMoveNoMapPoseAndAreCounted) {
  const auto key = make_keys(dir_.path() / "cvo-slam.key", 1);
  const auto other = make_keys(dir_.path() / "other-deployment.key", 1);
  const auto recording = dir_.path() / "clip.lcmlog";
  const auto conversion = cvo::testing::run_tool("tum2lcm",
                                                 cvo::testing::quoted(kClip) + " " + cvo::testing::quoted(recording) +
                                                     " --colour jpeg --key-file " + cvo::testing::quoted(key),
                                                 dir_.path());
  ASSERT_EQ(conversion.exit_code, 0) << conversion.err;

  Listener listener;
  auto backendd = start_backend(dir_.path(), key, "forged");
  const auto tracker_log = dir_.path() / "forged.trackerd.txt";
  auto trackerd = start_tracker(std::string("lcm:") + kUrl, key, tracker_log, false);
  ASSERT_TRUE(listener.wait_until([](const Heard& h) { return h.last_status.size() == 2; }, scaled(20s)))
      << cvo::testing::slurp(tracker_log);
  // A quarter of the recorded rate: frames keep coming well after the forgeries.
  DaemonProcess player(
      which("lcm-logplayer"),
      {"--lcm-url=" + std::string(kUrl), "-s", std::to_string(0.25 / cvo::testing::kSlowdown), recording.string()},
      dir_.path() / "player.txt");
  std::int64_t session = 0;
  std::vector<std::uint8_t> real;
  ASSERT_TRUE(listener.wait_until(
      [&](const Heard& h) {
        session = tracker_session(h);
        real = placing_map(h, session);
        return !real.empty();
      },
      scaled(30s)))
      << "no CVO_MAP placed the tracker's session\n"
      << cvo::testing::slurp(tracker_log);
  const auto forged = forged_from(real, session);
  auto forged_resigned = forged;  // what a daemon of another deployment on this bus would send
  auth::Signer(std::make_shared<const auth::KeyRing>(auth::read_key_file(other)), 0x6666)
      .sign("CVO_MAP", forged_resigned);
  const auto forged_revision =
      lcm::decode<cvo_lcm::map_t>(forged.data(), static_cast<int>(forged.size()), nullptr)->revision;
  {
    ::lcm::LCM attacker(kUrl);  // plain LCM: no key
    const std::vector<std::uint8_t>* const attacks[] = {&forged, &forged_resigned, &real};
    for (const auto* bytes : attacks) {
      attacker.publish("CVO_MAP", bytes->data(), static_cast<unsigned>(bytes->size()));
      std::this_thread::sleep_for(100ms);
    }
    // Keyframes of the live session with its next ids, unsigned: stored, they would have made the
    // genuine ones conflicts (BAD_CONFLICT) that never reach the map.
    auto next = lcm::decode<cvo_lcm::keyframe_t>(listener.snapshot().newest_keyframe.data(),
                                                 static_cast<int>(listener.snapshot().newest_keyframe.size()), nullptr);
    ASSERT_TRUE(next) << "no keyframe heard before the forgeries";
    const std::int64_t newest = next->id;
    next->auth = {};  // unsigned, as an attacker without the key sends it
    for (std::int64_t id = newest + 1; id <= newest + 3; ++id) {
      next->id = id;
      next->pose.position[0] += 0.3;
      const auto bytes = lcm::encode(*next);
      attacker.publish("CVO_KEYFRAME", bytes.data(), static_cast<unsigned>(bytes.size()));
    }
    {  // and a slice of the next one (slices are signed one by one)
      next->id = newest + 4;
      const auto message = lcm::encode(*next);
      const auto slice = lcm::encode(lcm::slice(message, {session, next->id, cvo_lcm::keyframe_chunk_t::KEYFRAME},
                                                lcm::content_crc(message.data(), message.size()), 0));
      attacker.publish("CVO_KEYFRAME_CHUNK", slice.data(), static_cast<unsigned>(slice.size()));
    }
    cvo_lcm::keyframe_request_t request{};  // the amplifier: each would re-send a keyframe of ~100 kB
    request.version = cvo_lcm::keyframe_request_t::SCHEMA_VERSION;
    request.session = session;
    request.ids = {0};
    request.num_ids = 1;
    for (int i = 0; i < 50; ++i) {  // in a second (a faster burst only overflows LCM's queue: fewer are seen)
      const auto bytes = lcm::encode(request);
      attacker.publish("CVO_KEYFRAME_REQUEST", bytes.data(), static_cast<unsigned>(bytes.size()));
      std::this_thread::sleep_for(20ms);
    }
  }
  const auto poses_at_forgery = listener.snapshot().poses.size();
  EXPECT_TRUE(player.wait_for(scaled(60s))) << "lcm-logplayer did not finish";
  std::this_thread::sleep_for(scaled(1500ms));
  trackerd->signal(SIGTERM);
  EXPECT_EQ(trackerd->wait_for(scaled(10s)).value_or(-9), 0) << cvo::testing::slurp(tracker_log);
  std::this_thread::sleep_for(300ms);

  const Heard heard = listener.snapshot();
  ASSERT_GT(heard.poses.size(), poses_at_forgery + 5) << "frames were tracked after the forgeries";
  for (const auto& p : heard.poses) EXPECT_NE(p.map_revision, forged_revision) << "frame " << p.frame_index;
  EXPECT_LT(largest_map_shift_m(heard.poses), 0.25) << "the forged correction moved a map pose";
  const auto& status = heard.last_status.at("cvo-trackerd");
  EXPECT_EQ(status.bus, std::int8_t{S::BUS_AUTHENTICATED});
  EXPECT_EQ(status.bad_messages[S::BAD_AUTH], 2 + 50)
      << "the copied forgery, the one of another deployment and the keyframe requests";
  EXPECT_EQ(status.keyframes_requested, 0) << "no keyframe sent again (the genuine back end lost none)";
  EXPECT_EQ(status.bad_messages[S::BAD_REPLAY], 1) << "the real map, sent again";
  const auto& backend = heard.last_status.at("cvo-backendd");
  EXPECT_EQ(backend.bad_messages[S::BAD_AUTH], 3 + 1)
      << "the keyframes (and slice) forged for the live session's next ids";
  EXPECT_EQ(backend.bad_messages[S::BAD_REPLAY] + backend.bad_messages[S::BAD_CONFLICT], 0)
      << "the genuine tracker's messages are all accepted";
  std::int64_t genuine_after = 0;  // genuine maps still applied after the forgeries
  for (std::size_t i = poses_at_forgery; i < heard.poses.size(); ++i) genuine_after = heard.poses[i].map_revision;
  EXPECT_GE(genuine_after, 0);
  const std::string log = cvo::testing::slurp(tracker_log);
  EXPECT_NE(log.find("bus authenticated"), std::string::npos) << log;
  backendd->signal(SIGTERM);
  EXPECT_EQ(backendd->wait_for(scaled(60s)).value_or(-9), 0);
  // The final map holds every genuine keyframe, those with the forged ones' ids too.
  EXPECT_TRUE(listener.wait_until([](const Heard& h) { return h.map_holds_every_keyframe(); }, scaled(10s)));
}

// A tracker of another deployment, and one on an open bus, next to a back end that holds the key.
TEST_F(AuthenticatedBus, ADaemonWithoutThisDeploymentsKeyIsRefusedWhole) {
  const auto key = make_keys(dir_.path() / "cvo-slam.key", 1);
  const auto other = make_keys(dir_.path() / "other-deployment.key", 1);
  Listener listener;
  auto backendd = start_backend(dir_.path(), key, "refused");
  ASSERT_TRUE(listener.wait_until([](const Heard& h) { return h.last_status.count("cvo-backendd") > 0; }, scaled(20s)));
  for (const std::optional<fs::path>& tracker_key : {std::optional<fs::path>(other), std::optional<fs::path>()}) {
    const auto tracker_log = dir_.path() / (tracker_key ? "other.trackerd.txt" : "open.trackerd.txt");
    auto trackerd = start_tracker("tum:" + kClip.string(), tracker_key, tracker_log, true);
    EXPECT_EQ(trackerd->wait_for(scaled(60s)).value_or(-9), 0) << cvo::testing::slurp(tracker_log);
  }
  std::this_thread::sleep_for(scaled(2s));  // two status periods of the back end
  const Heard heard = listener.snapshot();
  ASSERT_FALSE(heard.keyframes.empty());
  const auto& backend = heard.last_status.at("cvo-backendd");
  const auto sent = static_cast<std::int64_t>(heard.poses.size() + 2 * heard.keyframes.size());  // + local graphs
  EXPECT_GE(backend.bad_messages[S::BAD_AUTH], sent * 9 / 10) << "every pose, keyframe and local graph refused";
  EXPECT_EQ(backend.bad_messages[S::BAD_REPLAY], 0);
  EXPECT_FALSE(heard.map && !heard.map->keyframes.empty()) << "nothing of theirs reached the map";
  backendd->signal(SIGTERM);
  EXPECT_EQ(backendd->wait_for(scaled(60s)).value_or(-9), 0);
  // Nothing was stored: the store holds no record (its file header alone, or nothing).
  const auto store = dir_.path() / "refused.store";
  EXPECT_LT(fs::exists(store) ? fs::file_size(store) : 0, 100u);
}

// Neighbouring steps of a rotation (cvo-keygen --add, --rotate) on one bus: every keyframe reaches
// the map, the tracker applies the back end's maps, nothing is refused.
TEST_F(AuthenticatedBus, NeighbouringStepsOfARotationInteroperate) {
  const auto old_only = make_keys(dir_.path() / "old.key", 1);
  const auto added = dir_.path() / "old-new.key";  // --add: {old, new}
  {
    auto keys = auth::read_key_file(old_only).release();
    keys.push_back(auth::Key::generate());
    auth::create_key_file(added, auth::KeyRing(std::move(keys)));
  }
  const auto rotated = swapped(added, dir_.path() / "new-old.key");  // --rotate: {new, old}
  const std::vector<std::pair<fs::path, fs::path>> pairs{{added, old_only}, {rotated, added}};
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const auto& [tracker_key, backend_key] = pairs[i];
    const std::string name = "rotation" + std::to_string(i);
    Listener listener;
    auto backendd = start_backend(dir_.path(), backend_key, name);
    ASSERT_TRUE(
        listener.wait_until([](const Heard& h) { return h.last_status.count("cvo-backendd") > 0; }, scaled(20s)));
    const auto tracker_log = dir_.path() / (name + ".trackerd.txt");
    auto trackerd = start_tracker("tum:" + kClip.string(), tracker_key, tracker_log, true);
    EXPECT_EQ(trackerd->wait_for(scaled(60s)).value_or(-9), 0) << cvo::testing::slurp(tracker_log);
    EXPECT_TRUE(listener.wait_until([](const Heard& h) { return h.map_holds_every_keyframe(); }, scaled(30s)))
        << name << ": a keyframe did not reach the map";
    backendd->signal(SIGTERM);
    EXPECT_EQ(backendd->wait_for(scaled(60s)).value_or(-9), 0);
    const Heard heard = listener.snapshot();
    const bool applied =
        std::any_of(heard.poses.begin(), heard.poses.end(), [](const auto& p) { return p.map_revision >= 0; });
    EXPECT_TRUE(applied) << name << ": the tracker applied no map of the back end";
    for (const auto& [process, status] : heard.last_status) {
      EXPECT_EQ(status.bad_messages[S::BAD_AUTH], 0) << name << " " << process;
      EXPECT_EQ(status.bad_messages[S::BAD_REPLAY], 0) << name << " " << process;
    }
  }
}

}  // namespace
}  // namespace cvo::daemon
