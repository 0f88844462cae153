#pragma once
// What the back-end tests feed cvo-backendd: a real cvo-trackerd's CVO_KEYFRAME and
// CVO_LOCAL_GRAPH messages on the embedded clip, recorded once through a file:// provider, in the
// order the tracker published them.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "tests/support/daemon_process.hpp"
#include "tests/support/run_tool.hpp"

namespace cvo::testing {

struct Message {
  std::string channel;
  std::vector<std::uint8_t> bytes;
};

/// cvo-trackerd --deterministic on `folder` (tests/data/fr1_rpy_50 unless told), unpaced, with
/// `settings` ("key=value", each passed as --set) on top; its log and stderr go to `dir`.
inline std::vector<Message> tracker_recording(
    const std::filesystem::path& dir, const std::vector<std::string>& settings = {},
    const std::filesystem::path& folder = std::filesystem::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50") {
  using namespace std::chrono_literals;
  const auto out = dir / "tracker.lcmlog";
  std::vector<std::string> args{"--source",      "tum:" + folder.string(),
                                "--exit-on-eof", "--deterministic",
                                "--lcm-url",     "file://" + out.string() + "?mode=w",
                                "--set",         "trackerd.paced=false",
                                "--set",         "trackerd.realtime_priority=0",
                                "--set",         "trackerd.lock_memory=false"};
  for (const auto& s : settings) args.insert(args.end(), {"--set", s});
  DaemonProcess trackerd(std::filesystem::path(CVO_TOOLS_DIR) / "cvo-trackerd", args, dir / "tracker.txt");
  EXPECT_EQ(trackerd.wait_for(120s).value_or(-9), 0) << slurp(dir / "tracker.txt");
  std::vector<Message> messages;
  ::lcm::LogFile in(out.string(), "r");
  while (const ::lcm::LogEvent* e = in.readNextEvent()) {
    if (e->channel != "CVO_KEYFRAME" && e->channel != "CVO_LOCAL_GRAPH") continue;
    const auto* data = static_cast<const std::uint8_t*>(e->data);
    messages.push_back({e->channel, std::vector<std::uint8_t>(data, data + e->datalen)});
  }
  return messages;
}

}  // namespace cvo::testing
