// CVO_KEYFRAME as cvo-backendd receives it (and reads it back from its store): decode, then
// from_message, which decodes the keyframe's images and checks its pose and points.
#include "cvo_lcm/keyframe_t.hpp"
#include "fuzz/lcm_harness.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cvo::fuzz::fuzz_message<cvo_lcm::keyframe_t>(data, size, [](const cvo_lcm::keyframe_t& message) {
    std::string error;
    cvo::lcm::ContentFailure failure{};
    (void)cvo::lcm::from_message(message, &error, &failure);
  });
  return 0;
}
