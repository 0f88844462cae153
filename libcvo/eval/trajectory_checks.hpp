#pragma once
// The evaluation's view of an input trajectory. The TUM scripts read poses into a dict keyed by
// timestamp, so a repeated timestamp silently keeps only the last pose; here it is an error
// instead, because it always means a broken file or a broken writer.
#include <string_view>

#include "libcvo/core/trajectory.hpp"

namespace cvo::eval {

/// A copy sorted by timestamp. Throws std::invalid_argument, naming `what` (e.g. "estimate") and
/// the timestamp, when two poses share a timestamp.
core::Trajectory sorted_unique(const core::Trajectory& trajectory, std::string_view what);

}  // namespace cvo::eval
