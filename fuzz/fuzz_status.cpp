// CVO_STATUS as cvo-log status and the back end read it: decode only (it carries counters and text,
// no conversion).
#include "cvo_lcm/status_t.hpp"
#include "fuzz/lcm_harness.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cvo::fuzz::fuzz_message<cvo_lcm::status_t>(data, size, [](const cvo_lcm::status_t&) {});
  return 0;
}
