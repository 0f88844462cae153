#pragma once
// TUM trajectory files: one pose per line, "timestamp tx ty tz qx qy qz qw", '#' comments.
#include <filesystem>
#include <iosfwd>

#include "libcvo/core/trajectory.hpp"

namespace cvo::io {

/// Reads a TUM trajectory, sorted by timestamp. Throws InputError naming file and line on a
/// missing file, a malformed line, a non-finite value or a zero quaternion.
core::Trajectory read_tum_trajectory(const std::filesystem::path& file);
core::Trajectory parse_tum_trajectory(std::istream& in, const std::filesystem::path& name_for_errors);

/// Writes with full precision (timestamps to the microsecond and beyond); throws InputError when
/// the file cannot be written.
void write_tum_trajectory(const std::filesystem::path& file, const core::Trajectory& trajectory);
void write_tum_trajectory(std::ostream& out, const core::Trajectory& trajectory);

}  // namespace cvo::io
