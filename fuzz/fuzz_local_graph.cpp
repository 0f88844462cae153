// CVO_LOCAL_GRAPH as cvo-backendd receives it: decode, then from_message (nodes, edges, information
// matrices checked by core::check_information).
#include "cvo_lcm/local_graph_t.hpp"
#include "fuzz/lcm_harness.hpp"
#include "libcvo/lcm/local_graph_conversion.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cvo::fuzz::fuzz_message<cvo_lcm::local_graph_t>(data, size, [](const cvo_lcm::local_graph_t& message) {
    std::string error;
    cvo::lcm::ContentFailure failure{};
    (void)cvo::lcm::from_message(message, &error, &failure);
  });
  return 0;
}
