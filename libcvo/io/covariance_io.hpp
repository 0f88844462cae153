#pragma once
// Covariance files (cvo-run --covariance-out, cvo-eval --covariance): one line per frame,
//   timestamp c00 c01 ... c05 c10 ... c55
// the 36 entries of a 6x6 covariance, row-major, in [rho; phi] (core::SE3's tangent); '#' starts a
// comment. Frames without a covariance have no line.
#include <filesystem>
#include <iosfwd>
#include <vector>

#include "libcvo/core/se3.hpp"

namespace cvo::io {

struct StampedCovariance {
  double timestamp = 0;
  core::Matrix6d covariance = core::Matrix6d::Zero();
};

/// Throws InputError (file:line) on a line without 37 finite numbers or with an asymmetric matrix.
std::vector<StampedCovariance> read_covariances(const std::filesystem::path& file);
std::vector<StampedCovariance> parse_covariances(std::istream& in, const std::filesystem::path& name_for_errors);

void write_covariances(std::ostream& out, const std::vector<StampedCovariance>& covariances);
/// Throws InputError when the file cannot be written.
void write_covariances(const std::filesystem::path& file, const std::vector<StampedCovariance>& covariances);

}  // namespace cvo::io
