// CVO_GRID as a planner's bridge or a test reads it: decode, then from_message (sizes, values,
// frame and pose checked).
#include "cvo_lcm/grid_t.hpp"
#include "fuzz/lcm_harness.hpp"
#include "libcvo/lcm/grid_conversion.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cvo::fuzz::fuzz_message<cvo_lcm::grid_t>(data, size, [](const cvo_lcm::grid_t& message) {
    std::string error;
    cvo::lcm::ContentFailure failure{};
    (void)cvo::lcm::from_message(message, &error, &failure);
  });
  return 0;
}
