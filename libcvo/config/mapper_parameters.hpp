#pragma once
// The configuration mapped onto the loop detector and the back end, for the programs that run the
// back end (cvo-run --mode slam, cvo-backendd); module_parameters.hpp says which keys go where.
// Target cvo::mapper_parameters: it links loop closure and the back end, which the tracker does not.
#include "libcvo/config/config.hpp"
#include "libcvo/loop_closure/loop_verification.hpp"
#include "libcvo/slam/backend.hpp"
#include "libcvo/slam/mapper.hpp"

namespace cvo::config {

/// The loop detector: detection, matching, RANSAC, CVO refinement.
loop_closure::LoopDetectorParameters loop_detector_parameters(const Config& config);
/// The back end's pose-graph optimisations.
slam::BackendParameters backend_parameters(const Config& config);
/// The SLAM back end (cvo-run --mode slam, cvo-backendd): the two above.
slam::MapperParameters mapper_parameters(const Config& config);

}  // namespace cvo::config
