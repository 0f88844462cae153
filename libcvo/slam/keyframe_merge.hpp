#pragma once
// The edge algebra of merging a keyframe k into a keyframe c that covers its view (issue #27 item 3,
// slam/mapper.hpp says when): k stops being a node and becomes an alias, X_k = X_c · T with
// T = T_c^k fixed (the verified loop's measurement), and its edges become edges of c.
//
// posegraph's residual of an edge (i, j) with measurement Z is e = log(Z⁻¹ X_i⁻¹ X_j) (to first order).
//   leaving k, (k, j):   Z' = T · Z. Then Z⁻¹ X_k⁻¹ X_j = Z'⁻¹ X_c⁻¹ X_j: the same residual, Ω' = Ω.
//   arriving, (i, k):    Z' = Z · T⁻¹. Then Z⁻¹ X_i⁻¹ X_c T = T⁻¹ exp(e') T = exp(Ad(T⁻¹) e'),
//                        so e = Ad(T⁻¹) e' and Ω' = Ad(T⁻¹)ᵀ Ω Ad(T⁻¹): the same cost, moved.
//   reversed, (j, i):    Z' = Z⁻¹, e = -Ad(Z⁻¹) e', Ω' = Ad(Z⁻¹)ᵀ Ω Ad(Z⁻¹).
// Each is exact for the quadratic cost to first order; nothing is lost but k's own degrees of freedom.
//
// Fusion: two edges between the same nodes (a revisit's k→k' on top of the first visit's c→c') are
// two measurements of one relative pose: in the tangent space at the existing one Z₀,
// δ = log(Z₀⁻¹ Z₁), the information-weighted mean is Z = Z₀ · exp((Ω₀ + Ω₁)⁻¹ Ω₁ δ) and its
// information Ω₀ + Ω₁ (the sum of the two quadratics to first order). So the graph keeps one edge per
// pair of nodes it ever linked: its size follows the area, not the time spent in it.
//
// Chaining: a keyframe k merged into b (T_b^k, Ω₂) whose covering keyframe b is merged into a in
// turn (T_a^b, Ω₁) is re-pointed at a, so that an alias always names a node of the graph. With
// X_b = X_a T_a^b exp(e₁) and X_k = X_b T_b^k exp(e₂): X_k = X_a T_a^b T_b^k exp(Ad(T_b^k⁻¹) e₁ + e₂)
// to first order, so the chained edge is Z = T_a^b T_b^k with covariance Ad(T_b^k⁻¹) Σ₁ Ad(T_b^k⁻¹)ᵀ + Σ₂,
// i.e. information Ω = (Ω₁'⁻¹ + Ω₂⁻¹)⁻¹ = Ω₁' (Ω₁' + Ω₂)⁻¹ Ω₂ with Ω₁' = Ad(T_b^k)ᵀ Ω₁ Ad(T_b^k) (the
// second form needs only Ω₁' + Ω₂ invertible, so a semi-definite Ω of either edge is no trouble).
#include <optional>

#include "libcvo/core/se3.hpp"
#include "libcvo/posegraph/pose_graph.hpp"

namespace cvo::slam {

/// Keyframe `alias` is `covering` · relative (T_covering^alias).
struct KeyframeAlias {
  posegraph::NodeId alias = 0;
  posegraph::NodeId covering = 0;
  core::SE3 relative;
};

/// `edge` with the alias's end moved onto the covering keyframe (unchanged if it has no such end).
[[nodiscard]] posegraph::Edge reroute(const posegraph::Edge& edge, const KeyframeAlias& alias);
/// The same constraint as an edge to → from.
[[nodiscard]] posegraph::Edge reversed(const posegraph::Edge& edge);
/// `added` fused into `existing` (same nodes, either direction): the result runs as `existing` does.
[[nodiscard]] posegraph::Edge fused(const posegraph::Edge& existing, const posegraph::Edge& added);
/// `first` (a -> b) followed by `second` (b -> k): the edge a -> k (see Chaining above). Throws
/// std::invalid_argument when second does not start where first ends.
[[nodiscard]] posegraph::Edge chained(const posegraph::Edge& first, const posegraph::Edge& second);
/// What `whole` (same nodes and direction) holds beyond `part`: the edge d with fused(part, d) =
/// whole to first order, Ω_d = Ω_whole − Ω_part and, at Z_part, δ_d = Ω_d⁻¹ Ω_whole log(Z_part⁻¹ Z_whole).
/// nullopt when Ω_d is not positive definite (whole holds nothing beyond part: a repeat).
[[nodiscard]] std::optional<posegraph::Edge> increment(const posegraph::Edge& part, const posegraph::Edge& whole);

}  // namespace cvo::slam
