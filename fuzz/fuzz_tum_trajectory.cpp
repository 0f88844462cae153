// TUM trajectories (ground truth, cvo-eval's inputs): parse_tum_trajectory.
#include <optional>
#include <sstream>

#include "fuzz/harness.hpp"
#include "libcvo/io/trajectory_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::optional<cvo::core::Trajectory> trajectory;
  cvo::fuzz::expect_refusal_or_success([&] {
    std::istringstream in{std::string(cvo::fuzz::as_text(data, size))};
    trajectory = cvo::io::parse_tum_trajectory(in, "<fuzz>");
  });
  if (!trajectory) return 0;
  // An accepted trajectory, written as cvo-run writes its output, must read again: outside the
  // refusal filter, so a refusal here is a finding.
  std::stringstream written;
  cvo::io::write_tum_trajectory(written, *trajectory);
  (void)cvo::io::parse_tum_trajectory(written, "<written>");
  return 0;
}
