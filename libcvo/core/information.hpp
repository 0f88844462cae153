#pragma once
// What an edge's information matrix must be, checked in this one place by every way into a pose
// graph: PoseGraph::add_edge, the g2o reader (posegraph/g2o_io.hpp), slam::Backend and the back
// end's door for CVO_LOCAL_GRAPH (lcm/local_graph_conversion.hpp); and the repair the g2o reader
// applies. In core, not posegraph: the wire library checks it too, and must not link the solver.
//
// An edge costs 1/2 e^T Omega e (pose_graph.hpp). That is a cost, never negative, only when Omega
// is symmetric positive semi-definite: an eigenvalue lambda < 0 with eigenvector v makes an error
// e = s v cost lambda s^2 / 2, so the optimiser gains by pushing the edge's error along v. The
// total is then unbounded below or has a negative minimum, and Levenberg-Marquardt stops there
// "converged" (or on a saddle): a wrong map that looks fine.
//
// Semi-definite, not definite: a zero eigenvalue is a direction the measurement does not
// constrain (CVO on a flat wall has no information along the wall); it costs nothing and the
// optimiser's damping handles it, so refusing it would throw away good local graphs.
// Tolerances are relative (to the largest |entry| or |eigenvalue|), so the check holds at every
// scale (CVO Hessians are ~1e2..1e8) and round-off (~1e-16 relative) never trips it.
//
// Repair (nearest_information): the symmetric positive semi-definite matrix nearest to A in the
// Frobenius norm is V max(Lambda, 0) V^T, where S = (A + A^T)/2 = V Lambda V^T (Higham 1988). The
// eigenvalues are clamped at kInformationRepairFloor * max|lambda| instead of 0, so the result is
// positive definite (a Cholesky factor exists, as Ceres' formulation needs) and within that floor
// of the nearest; a direction the input got wrong then carries (almost) no information.
#include <string>

#include "libcvo/core/se3.hpp"

namespace cvo::core {

inline constexpr double kInformationTolerance = 1e-9;    // relative: asymmetry and negative eigenvalues
inline constexpr double kInformationRepairFloor = 1e-9;  // relative: smallest eigenvalue after a repair

enum class InformationDefect {
  kNone,
  kNotFinite,     // a NaN or infinite entry
  kNotSymmetric,  // |Omega - Omega^T| > tolerance * max|Omega|
  kIndefinite,    // an eigenvalue below -tolerance * max|lambda|
};

struct InformationCheck {
  InformationDefect defect = InformationDefect::kNone;
  double smallest_eigenvalue = 0;  // of the symmetric part; 0 when not finite
  double largest_eigenvalue = 0;

  [[nodiscard]] bool ok() const { return defect == InformationDefect::kNone; }
  /// Empty when ok(); otherwise a phrase such as "information is not positive semi-definite
  /// (eigenvalues -0.2 .. 2.2)", for messages that name the edge or file:line first.
  [[nodiscard]] std::string why() const;
};

InformationCheck check_information(const core::Matrix6d& omega);

/// The repair above: exactly symmetric, positive definite (zero only for a zero omega), omega
/// itself up to round-off when omega is symmetric with every eigenvalue above the floor. Throws
/// std::invalid_argument when omega is not finite (there is nothing to repair towards).
core::Matrix6d nearest_information(const core::Matrix6d& omega);

}  // namespace cvo::core
