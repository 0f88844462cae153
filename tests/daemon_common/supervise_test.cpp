// The supervision loop both daemons run: it returns the stop signal that came (SIGHUP too, which
// would otherwise kill the process), or nothing when the daemon ended by itself, and serves
// systemd's watchdog only while every worker beats.
#include "daemon/common/supervise.hpp"

#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "daemon/common/signals.hpp"

namespace cvo::daemon {
namespace {

using namespace std::chrono_literals;

TEST(Supervise, ReturnsEachStopSignalSigHupIncluded) {
  block_stop_signals();  // this test's threads: as in a daemon
  const SystemdNotifier systemd;
  const Heartbeat beat;
  const Heartbeat* const beats[] = {&beat};
  for (const int signal : {SIGTERM, SIGINT, SIGHUP}) {
    ASSERT_EQ(kill(getpid(), signal), 0);
    const auto stopped = supervise(systemd, {beats, 5s}, [] { return false; });
    ASSERT_TRUE(stopped) << signal_name(signal);
    EXPECT_EQ(*stopped, signal);
  }
  EXPECT_STREQ(signal_name(SIGHUP), "SIGHUP");
}

TEST(Supervise, ReturnsNothingWhenTheDaemonEndsByItself) {
  block_stop_signals();
  const SystemdNotifier systemd;
  std::atomic<bool> done{false};
  std::thread worker([&] {
    std::this_thread::sleep_for(100ms);
    done = true;
  });
  const auto stopped = supervise(systemd, {{}, 5s}, [&] { return done.load(); });
  worker.join();
  EXPECT_FALSE(stopped);
}

// A notification socket stands in for systemd (sd_notify(3) writes datagrams to NOTIFY_SOCKET).
class NotificationSocket {
 public:
  NotificationSocket() : path_(std::filesystem::temp_directory_path() / ("cvo-notify-" + std::to_string(getpid()))) {
    std::filesystem::remove(path_);
    fd_ = socket(AF_UNIX, SOCK_DGRAM, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    path_.string().copy(address.sun_path, sizeof address.sun_path - 1);
    EXPECT_EQ(bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address), 0);
    timeval tv{0, 20000};
    setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  ~NotificationSocket() {
    close(fd_);
    std::filesystem::remove(path_);
  }
  [[nodiscard]] std::string path() const { return path_.string(); }
  /// Every datagram that came, one per line.
  std::string drain() {
    std::string out;
    char buffer[512];
    for (ssize_t n; (n = recv(fd_, buffer, sizeof buffer, 0)) > 0;)
      out.append(buffer, static_cast<std::size_t>(n)) += '\n';
    return out;
  }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

int count(const std::string& text, const std::string& word) {
  int n = 0;
  for (auto at = text.find(word); at != std::string::npos; at = text.find(word, at + 1)) ++n;
  return n;
}

TEST(Supervise, ServesTheWatchdogOnlyWhileEveryWorkerBeats) {
  block_stop_signals();
  NotificationSocket systemd_socket;
  setenv("NOTIFY_SOCKET", systemd_socket.path().c_str(), 1);
  setenv("WATCHDOG_USEC", "100000", 1);  // a ping every 50 ms
  const SystemdNotifier systemd;         // reads WATCHDOG_USEC now; sd_notify reads NOTIFY_SOCKET each time
  unsetenv("WATCHDOG_USEC");
  ASSERT_TRUE(systemd.watchdog_period());

  Heartbeat alive, hung;
  std::atomic<bool> done{false}, hang{false};
  std::thread worker([&] {
    while (!done) {
      alive.beat();
      if (!hang) hung.beat();
      std::this_thread::sleep_for(5ms);
    }
  });
  const Heartbeat* const beats[] = {&alive, &hung};
  std::thread supervisor([&] { supervise(systemd, {beats, 200ms}, [&] { return done.load(); }); });
  std::this_thread::sleep_for(500ms);
  const std::string beating = systemd_socket.drain();
  hang = true;  // one worker stops beating: after 200 ms of silence no more pings
  std::this_thread::sleep_for(300ms);
  systemd_socket.drain();
  std::this_thread::sleep_for(500ms);
  const std::string hung_log = systemd_socket.drain();
  done = true;
  supervisor.join();
  worker.join();
  EXPECT_GE(count(beating, "WATCHDOG=1"), 2) << beating;  // every 50 ms when the machine is idle
  EXPECT_EQ(count(hung_log, "WATCHDOG=1"), 0) << "pinged while a worker was hung:\n" << hung_log;
  EXPECT_EQ(count(systemd_socket.drain(), "STOPPING=1"), 1);
  unsetenv("NOTIFY_SOCKET");
}

}  // namespace
}  // namespace cvo::daemon
