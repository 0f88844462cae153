#pragma once
// A daemon under test: started with fork/exec (stderr to a file), signalled, waited for with a
// timeout, and killed if a test leaves it running. Tests of the daemons' lifecycle need exactly
// these controls, which popen() does not give.
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace cvo::testing {

class DaemonProcess {
 public:
  DaemonProcess(const std::filesystem::path& executable, const std::vector<std::string>& args,
                const std::filesystem::path& stderr_file,
                const std::vector<std::pair<std::string, std::string>>& env = {}) {
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = open(stderr_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) dup2(fd, 2);
      const int null = open("/dev/null", O_WRONLY);
      if (null >= 0) dup2(null, 1);
      for (const auto& [k, v] : env) setenv(k.c_str(), v.c_str(), 1);
      std::vector<char*> argv{const_cast<char*>(executable.c_str())};
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      execv(executable.c_str(), argv.data());
      _exit(127);
    }
  }
  ~DaemonProcess() {
    if (running()) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  [[nodiscard]] pid_t pid() const { return pid_; }
  void signal(int sig) const { kill(pid_, sig); }

  /// The exit status once the process has exited within `timeout` (-1 for death by a signal);
  /// nullopt while it is still running.
  std::optional<int> wait_for(std::chrono::milliseconds timeout) {
    if (exit_code_) return exit_code_;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
      int status = 0;
      if (wait4(pid_, &status, WNOHANG, &usage_) == pid_) {
        exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        return exit_code_;
      }
      if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  bool running() { return !wait_for(std::chrono::milliseconds(0)).has_value(); }
  /// Once it has exited (wait_for): its peak resident set (the kernel's maxrss of this child), in bytes.
  [[nodiscard]] long peak_rss_bytes() const { return usage_.ru_maxrss * 1024L; }

 private:
  pid_t pid_ = -1;
  std::optional<int> exit_code_;
  rusage usage_{};
};

}  // namespace cvo::testing
