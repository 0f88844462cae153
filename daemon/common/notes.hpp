#pragma once
// What a daemon tells its operator: each note goes to stderr (the journal under systemd) prefixed
// with the process's name, and the last one is CVO_STATUS's `detail`. One log-rate policy for
// every repeated event (a flood of bad messages, a lossy link): a kind of note is written at most
// once a second, and the next one says how many like it were held back. Thread-safe; it
// allocates, so a realtime thread only counts and leaves the noting to another thread.
#include <chrono>
#include <map>
#include <mutex>
#include <string>

namespace cvo::daemon {

class Notes {
 public:
  explicit Notes(std::string process) : process_(std::move(process)) {}

  void note(const std::string& detail);
  /// note(), at most once per `period` for each `kind`.
  void note_limited(const std::string& kind, const std::string& detail);
  /// The last note written.
  [[nodiscard]] std::string last() const;

  static constexpr std::chrono::seconds period{1};

 private:
  struct Limit {
    std::chrono::steady_clock::time_point last{};
    long long held_back = 0;
  };
  const std::string process_;
  mutable std::mutex mutex_;
  std::string last_;
  std::map<std::string, Limit> limits_;
};

}  // namespace cvo::daemon
