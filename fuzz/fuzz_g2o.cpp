// g2o pose-graph files (pgo-bench, datasets): parse_g2o, repairs of information matrices included.
#include <sstream>

#include "fuzz/harness.hpp"
#include "libcvo/posegraph/g2o_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cvo::fuzz::expect_refusal_or_success([&] {
    std::istringstream in{std::string(cvo::fuzz::as_text(data, size))};
    std::ostringstream warnings;  // a repaired matrix is a warning, not a finding
    (void)cvo::posegraph::parse_g2o(in, "<fuzz>", warnings);
  });
  return 0;
}
