// Intrinsics files (YAML or ETH3D calibration.txt), as --camera FILE and a folder's camera.yaml.
#include <optional>

#include "fuzz/harness.hpp"
#include "libcvo/io/intrinsics_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::optional<cvo::core::Intrinsics> intrinsics;
  cvo::fuzz::expect_refusal_or_success(
      [&] { intrinsics = cvo::io::parse_intrinsics(cvo::fuzz::as_text(data, size), "<fuzz>"); });
  // What was accepted, written as cvo-render writes camera.yaml, must read again: outside the
  // refusal filter, so a refusal here is a finding. Not for a calibration.txt without an image
  // size (width = height = 0): the YAML form requires one.
  if (intrinsics && intrinsics->width > 0)
    (void)cvo::io::parse_intrinsics(cvo::io::format_intrinsics_yaml(*intrinsics, "fuzz"), "<formatted>");
  return 0;
}
