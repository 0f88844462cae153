// "--set section.key=value" assignments: each line of the input is one apply_override on the
// defaults, as the daemons and cvo-run apply them in order.
#include <string_view>

#include "fuzz/harness.hpp"
#include "libcvo/config/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cvo::config::Config config;
  std::string_view rest = cvo::fuzz::as_text(data, size);
  while (!rest.empty()) {
    const auto end = rest.find('\n');
    const std::string_view assignment = rest.substr(0, end);
    rest.remove_prefix(end == std::string_view::npos ? rest.size() : end + 1);
    const cvo::config::Config before = config;
    try {
      cvo::config::apply_override(config, assignment);
    } catch (const cvo::config::ConfigError&) {
      // config.hpp's promise: a refused assignment leaves the configuration as it was.
      if (!(config == before)) cvo::fuzz::fail("a refused --set changed the configuration");
    }
  }
  return 0;
}
