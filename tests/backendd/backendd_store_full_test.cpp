// cvo-backendd when its keyframe store cannot be written, end to end over LCM UDP multicast with a
// real tracker's keyframes and local graphs:
// - on a full disk (ENOSPC: a tiny tmpfs, filled) and under a file-size limit (EFBIG: prlimit;
//   SIGXFSZ must not kill it), the daemon keeps running and uses every message; CVO_STATUS says
//   STATE_DEGRADED with unsaved_records, systemd's STATUS= "degraded: store full (N records
//   unsaved)..."; a repeat of a stored and of a held message meanwhile is not stored twice;
// - once there is room again every held record is written, in order, the state is back to normal,
//   and a restart recovers every record.
//
// Runs only inside tests/support/in-private-netns; the full disk also inside
// tests/support/in-private-mountns (CVO_SMALL_FS: a tmpfs no other process sees).
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/statvfs.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "libcvo/store/keyframe_store.hpp"
#include "libcvo/store/message_door.hpp"
#include "tests/backendd/netns_support.hpp"
#include "tests/backendd/tracker_recording.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::Captured;
using cvo::testing::DaemonProcess;
using cvo::testing::KeyframeName;
using cvo::testing::LcmCapture;
using cvo::testing::Message;
using cvo::testing::slurp;

// systemd's side of sd_notify: a datagram socket whose STATUS= lines are collected as they come.
// Its path must fit sockaddr_un (108 bytes), which a test's temporary folder may not.
class NotifySocket {
 public:
  NotifySocket() : path_(fs::temp_directory_path() / ("cvo-notify-" + std::to_string(::getpid()) + ".sock")) {
    fs::remove(path_);
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", path_.c_str());
    EXPECT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0) << path_;
  }
  ~NotifySocket() {
    ::close(fd_);
    ::unlink(path_.c_str());
  }
  NotifySocket(const NotifySocket&) = delete;
  NotifySocket& operator=(const NotifySocket&) = delete;

  [[nodiscard]] const fs::path& path() const { return path_; }
  /// Every STATUS= text received so far, in order.
  const std::vector<std::string>& statuses() {
    char buffer[4096];
    for (ssize_t n; (n = ::recv(fd_, buffer, sizeof buffer, MSG_DONTWAIT)) > 0;) {
      const std::string datagram(buffer, static_cast<std::size_t>(n));
      std::smatch m;
      if (std::regex_search(datagram, m, std::regex("(^|\n)STATUS=([^\n]*)"))) statuses_.push_back(m[2]);
    }
    return statuses_;
  }

 private:
  fs::path path_;
  int fd_ = -1;
  std::vector<std::string> statuses_;
};

// How the store is kept from writing, and how room is made again.
struct Squeeze {
  std::vector<std::string> wrapper;        // runs cvo-backendd (prlimit ...), or empty
  std::function<void(int pid)> make_room;  // the daemon's pid
  std::string status_prefix;               // systemd's STATUS= meanwhile
};

class BackenddStoreFull : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!cvo::testing::udp_test_skip_reason().empty()) return;
    const cvo::test::TempDir dir("backendd_recording");
    messages_ = cvo::testing::tracker_recording(dir.path());
  }

  void SetUp() override {
    if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
    ASSERT_GE(messages_.size(), 12u) << "the tracker made too few keyframes";
  }

  // Bytes the store takes for its magic and the first third of the messages: room for those,
  // and for half the next one (a keyframe, far more than a tmpfs page: a local graph's half could
  // fit in the last page's slack), so that it is the first write to fail, half-way, and every
  // record after it is held.
  static std::size_t room_for_a_third() {
    std::size_t bytes = 8;
    for (std::size_t i = 0; i < stored_first(); ++i) bytes += 16 + messages_[i].bytes.size();
    return bytes + messages_[stored_first()].bytes.size() / 2;
  }
  static std::size_t stored_first() {
    std::size_t i = messages_.size() / 3;
    while (i + 1 < messages_.size() && messages_[i].channel != "CVO_KEYFRAME") ++i;
    return i;
  }

  static std::set<KeyframeName> all_keyframes() {
    std::set<KeyframeName> names;
    for (const auto& m : messages_) {
      if (m.channel != "CVO_KEYFRAME") continue;
      const auto message =
          store::identify(store::RecordKind::kKeyframe, m.bytes.data(), m.bytes.size(), nullptr, nullptr);
      if (message) names.emplace(message->key.session, message->key.id);
    }
    return names;
  }

  // Publishes as a tracker would; 10 Hz, so that nothing overflows a socket.
  static void send(const std::vector<Message>& messages) {
    ::lcm::LCM lcm(cvo::testing::kUrl);
    for (const auto& m : messages) {
      lcm.publish(m.channel, m.bytes.data(), static_cast<unsigned int>(m.bytes.size()));
      std::this_thread::sleep_for(100ms);
    }
  }

  void degrade_and_recover(const fs::path& store, const Squeeze& squeeze);
  static void restart_recovers_everything(const fs::path& store, const fs::path& dir);

  static std::vector<Message> messages_;
};

std::vector<Message> BackenddStoreFull::messages_;

// cvo-backendd, run by `wrapper` (a command and its arguments, or nothing), telling `notify`.
std::unique_ptr<DaemonProcess> start_daemon(const std::vector<std::string>& wrapper, const fs::path& store,
                                            const fs::path& stderr_file, const NotifySocket* notify) {
  fs::path executable = fs::path(CVO_TOOLS_DIR) / "cvo-backendd";
  std::vector<std::string> args{"--lcm-url", cvo::testing::kUrl, "--store", store.string()};
  if (!wrapper.empty()) {
    args.insert(args.begin(), executable.string());
    args.insert(args.begin(), wrapper.begin() + 1, wrapper.end());
    executable = wrapper.front();
  }
  std::vector<std::pair<std::string, std::string>> env;
  if (notify != nullptr) env.emplace_back("NOTIFY_SOCKET", notify->path().string());
  return std::make_unique<DaemonProcess>(executable, args, stderr_file, env);
}

// The store holds every message once, in the order sent, and reads back without a warning.
void expect_every_message_stored_once(const fs::path& store, const std::vector<Message>& messages) {
  std::vector<store::StoredRecord> records;
  std::string warning;
  store::KeyframeStore reopened(store, records, warning);
  EXPECT_TRUE(warning.empty()) << warning;
  ASSERT_EQ(records.size(), messages.size()) << "neither lost nor stored twice";
  for (std::size_t i = 0; i < records.size(); ++i)
    EXPECT_TRUE(records[i].payload == messages[i].bytes) << "record " << i << " is message " << i;
}

void BackenddStoreFull::degrade_and_recover(const fs::path& store, const Squeeze& squeeze) {
  const cvo::test::TempDir dir;
  LcmCapture capture(dir.path() / "maps.lcmlog");
  ASSERT_TRUE(capture.good());
  NotifySocket notify;
  const auto err = dir.path() / "backendd.txt";
  auto backendd = start_daemon(squeeze.wrapper, store, err, &notify);
  const int pid = backendd->pid();
  ASSERT_TRUE(capture.wait_until([&](const Captured& c) { return c.status_from(pid); }, 60s)) << slurp(err);

  // Every message, then a repeat of the first (stored) and of the last (held by then).
  send(messages_);
  send({messages_.front(), messages_.back()});
  // Every keyframe used; CVO_STATUS degraded with every record after the first third unsaved,
  // and systemd told as many.
  const auto all = all_keyframes();
  const auto unsaved = static_cast<std::int64_t>(messages_.size() - stored_first());
  const auto said_unsaved = [&]() -> std::string {  // N of "<prefix>N records unsaved)", or ""
    const auto& texts = notify.statuses();
    if (texts.empty() || !texts.back().starts_with(squeeze.status_prefix)) return {};
    const std::string rest = texts.back().substr(squeeze.status_prefix.size());
    std::smatch m;
    return std::regex_search(rest, m, std::regex("^(\\d+) records? unsaved\\)")) ? m[1].str() : "";
  };
  const auto degraded = [&](const Captured& c) {
    const auto& s = c.backend_statuses.back();
    return c.map_holds(all) && s.pid == pid && s.state == cvo_lcm::status_t::STATE_DEGRADED &&
           s.unsaved_records == unsaved && said_unsaved() == std::to_string(unsaved);
  };
  ASSERT_TRUE(capture.wait_until(degraded, 120s))
      << "every keyframe used, and the degraded state said\n"
      << slurp(err) << (notify.statuses().empty() ? "no STATUS=" : notify.statuses().back());
  ASSERT_TRUE(backendd->running()) << slurp(err);
  std::cout << "while the store could not be written: " << unsaved << " of " << messages_.size()
            << " records unsaved; STATUS=" << notify.statuses().back() << std::endl;

  const auto before = capture.snapshot().backend_statuses.size();
  squeeze.make_room(pid);
  const auto recovered = [&](const Captured& c) {
    if (c.backend_statuses.size() <= before) return false;
    const auto& s = c.backend_statuses.back();
    if (s.pid != pid || s.state == cvo_lcm::status_t::STATE_DEGRADED || s.unsaved_records != 0) return false;
    const auto& texts = notify.statuses();
    return !texts.empty() && !texts.back().starts_with("degraded");
  };
  EXPECT_TRUE(capture.wait_until(recovered, 60s)) << "back to normal once there is room\n" << slurp(err);
  EXPECT_EQ(cvo::testing::stop(*backendd, 120s).value_or(-9), 0) << slurp(err);
  const auto log = slurp(err);
  EXPECT_NE(log.find("works again: every held record is stored (" + std::to_string(messages_.size()) + " records)"),
            std::string::npos)
      << log;
  EXPECT_EQ(log.find("lost on restart"), std::string::npos) << log;

  expect_every_message_stored_once(store, messages_);
  restart_recovers_everything(store, dir.path());
}

// A new daemon on the store: every record read back, every keyframe in its map.
void BackenddStoreFull::restart_recovers_everything(const fs::path& store, const fs::path& dir) {
  LcmCapture capture(dir / "maps2.lcmlog");  // the first daemon's maps are not this one's
  ASSERT_TRUE(capture.good());
  const auto err = dir / "backendd2.txt";
  auto backendd = start_daemon({}, store, err, nullptr);
  const int pid = backendd->pid();
  const auto all = all_keyframes();
  EXPECT_TRUE(capture.wait_until([&](const Captured& c) { return c.status_from(pid) && c.map_holds(all); }, 120s))
      << slurp(err);
  EXPECT_EQ(cvo::testing::stop(*backendd, 120s).value_or(-9), 0) << slurp(err);
  const auto log = slurp(err);
  EXPECT_NE(log.find("(" + std::to_string(messages_.size()) + " records recovered)"), std::string::npos) << log;
  EXPECT_EQ(log.find("intact records kept"), std::string::npos) << "nothing to recover from\n" << log;
}

// ENOSPC: the store on a tmpfs filled but for room for a third of the messages; the filler is
// removed to make room.
TEST_F(BackenddStoreFull, OnAFullDiskItDegradesAndOnceThereIsRoomLosesNothing) {
  const char* small = std::getenv("CVO_SMALL_FS");
  if (small == nullptr) GTEST_SKIP() << "runs only in tests/support/in-private-mountns (a tmpfs to fill)";
  const fs::path fs_root(small);
  struct statvfs st {};
  ASSERT_EQ(statvfs(small, &st), 0);
  const auto free_bytes = static_cast<std::size_t>(st.f_bavail) * st.f_bsize;
  const auto room = room_for_a_third();
  ASSERT_GT(free_bytes, 2 * room) << "the tmpfs is too small for this test";
  const auto filler = fs_root / "filler";
  {
    const int fd = ::open(filler.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(posix_fallocate(fd, 0, static_cast<off_t>(free_bytes - room)), 0);
    ::close(fd);
  }
  Squeeze squeeze{{}, [&](int) { fs::remove(filler); }, "degraded: store full ("};
  degrade_and_recover(fs_root / "state" / "keyframes.store", squeeze);
}

// EFBIG: cvo-backendd under a file-size limit of room for a third of the messages (SIGXFSZ would
// kill it unless ignored); the limit is lifted to make room.
TEST_F(BackenddStoreFull, UnderAFileSizeLimitItDegradesAndOnceLiftedLosesNothing) {
  const auto prlimit = cvo::testing::which("prlimit");
  if (prlimit.empty()) GTEST_SKIP() << "prlimit (util-linux) missing";
  const cvo::test::TempDir dir;
  const auto lift = [](int pid) {
    const rlimit unlimited{RLIM_INFINITY, RLIM_INFINITY};
    EXPECT_EQ(::prlimit(pid, RLIMIT_FSIZE, &unlimited, nullptr), 0);
  };
  Squeeze squeeze{{prlimit.string(), "--fsize=" + std::to_string(room_for_a_third()) + ":unlimited"},
                  lift,
                  "degraded: store at the file size limit ("};
  degrade_and_recover(dir.path() / "keyframes.store", squeeze);
}

}  // namespace
}  // namespace cvo::daemon
