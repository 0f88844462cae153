#include "libcvo/slam/keyframe_merge.hpp"

#include <stdexcept>

namespace cvo::slam {
namespace {

core::Matrix6d moved(const core::Matrix6d& information, const core::SE3& by) {
  const core::Matrix6d ad = by.adjoint();
  const core::Matrix6d out = ad.transpose() * information * ad;
  return 0.5 * (out + out.transpose());
}

}  // namespace

posegraph::Edge reroute(const posegraph::Edge& edge, const KeyframeAlias& alias) {
  posegraph::Edge out = edge;
  if (edge.from == alias.alias) {
    out.from = alias.covering;
    out.measurement = alias.relative * out.measurement;
  }
  if (edge.to == alias.alias) {
    const core::SE3 inverse = alias.relative.inverse();
    out.to = alias.covering;
    out.measurement = out.measurement * inverse;
    out.information = moved(out.information, inverse);
  }
  return out;
}

posegraph::Edge reversed(const posegraph::Edge& edge) {
  const core::SE3 inverse = edge.measurement.inverse();
  return {edge.to, edge.from, inverse, moved(edge.information, inverse), edge.robust};
}

posegraph::Edge fused(const posegraph::Edge& existing, const posegraph::Edge& added) {
  const bool same = added.from == existing.from && added.to == existing.to;
  if (!same && !(added.from == existing.to && added.to == existing.from))
    throw std::invalid_argument("fused: the edges join other nodes");
  const posegraph::Edge a = same ? added : reversed(added);
  const core::Matrix6d sum = existing.information + a.information;
  const core::Vector6d delta = (existing.measurement.inverse() * a.measurement).log();
  posegraph::Edge out = existing;
  out.measurement = existing.measurement * core::SE3::exp(sum.ldlt().solve(a.information * delta));
  out.information = sum;
  return out;
}

posegraph::Edge chained(const posegraph::Edge& first, const posegraph::Edge& second) {
  if (first.to != second.from)
    throw std::invalid_argument("chained: the second edge does not start where the first ends");
  const core::Matrix6d one = moved(first.information, second.measurement);  // Ω₁', at k
  const core::Matrix6d sum = one + second.information;
  const core::Matrix6d out = one * sum.ldlt().solve(second.information);
  posegraph::Edge e = second;
  e.from = first.from;
  e.measurement = first.measurement * second.measurement;
  e.information = 0.5 * (out + out.transpose());
  return e;
}

std::optional<posegraph::Edge> increment(const posegraph::Edge& part, const posegraph::Edge& whole) {
  if (part.from != whole.from || part.to != whole.to) throw std::invalid_argument("increment: other nodes");
  const core::Matrix6d more =
      0.5 * (whole.information - part.information + (whole.information - part.information).transpose());
  const Eigen::LDLT<core::Matrix6d> ldlt(more);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
      ldlt.vectorD().minCoeff() <= 1e-9 * whole.information.trace())
    return std::nullopt;
  const core::Vector6d delta = (part.measurement.inverse() * whole.measurement).log();
  posegraph::Edge out = part;
  out.measurement = part.measurement * core::SE3::exp(ldlt.solve(whole.information * delta));
  out.information = more;
  return out;
}

}  // namespace cvo::slam
