// The YAML configuration (--config FILE, /etc/cvo-slam/*.yaml): parse_config.
#include "fuzz/harness.hpp"
#include "libcvo/config/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cvo::fuzz::expect_refusal_or_success([&] {
    const auto config = cvo::config::parse_config(cvo::fuzz::as_text(data, size), "<fuzz>");
    // config.hpp's promise: every accepted configuration survives its own dump.
    if (!(cvo::config::parse_config(cvo::config::dump_config(config), "<dump>") == config))
      cvo::fuzz::fail("parse_config(dump_config(c)) != c");
  });
  return 0;
}
