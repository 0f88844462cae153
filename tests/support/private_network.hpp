#pragma once
// What the UDP multicast tests share: the LCM URL they use, the guard that they run only inside
// tests/support/in-private-netns, where the LCM command-line tools are, and why a test skips.
#include <cstdlib>
#include <filesystem>
#include <string>

namespace cvo::testing {

// recv_buf_size: a 640x480 frame is a burst of ~100 fragments; the kernel's default socket buffer
// overflows (LCM warns) and frames are lost. Capped by net.core.rmem_max.
inline constexpr const char* kPrivateLcmUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

/// True only inside in-private-netns (CVO_PRIVATE_NETNS=1): never send test traffic otherwise.
inline bool in_private_network_namespace() {
  const char* v = std::getenv("CVO_PRIVATE_NETNS");
  return v != nullptr && std::string(v) == "1";
}

/// The installed program (lcm-logger, lcm-logplayer), or an empty path.
inline std::filesystem::path which(const std::string& tool) {
  for (const char* dir : {"/usr/bin", "/usr/local/bin", "/bin"})
    if (std::filesystem::exists(std::filesystem::path(dir) / tool)) return std::filesystem::path(dir) / tool;
  return {};
}

/// Why a UDP multicast test cannot run here (outside in-private-netns, or without the LCM tools),
/// or empty when it can.
inline std::string udp_test_skip_reason() {
  if (!in_private_network_namespace())
    return "runs only in a private network namespace (tests/support/in-private-netns)";
  if (which("lcm-logger").empty() || which("lcm-logplayer").empty())
    return "lcm-logger/lcm-logplayer missing (liblcm-bin)";
  return {};
}

}  // namespace cvo::testing
