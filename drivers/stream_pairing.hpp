#pragma once
// Pairing a colour and a depth stream that arrive separately (two V4L2 nodes) by their capture
// times. Each stream keeps its newest unpaired frame; when both are waiting, pair_action() says
// what to do with them.
namespace cvo::drivers {

enum class PairAction { kPair, kDropColour, kDropDepth };

/// Colour stamped t_colour and depth stamped t_depth (seconds) both wait. Within max_dt they are
/// a pair. Otherwise the older one is dropped: the other stream's later frames are later still,
/// so they would be even further from it.
constexpr PairAction pair_action(double t_colour, double t_depth, double max_dt) {
  const double dt = t_colour - t_depth;
  if (dt <= max_dt && -dt <= max_dt) return PairAction::kPair;
  return dt < 0 ? PairAction::kDropColour : PairAction::kDropDepth;
}

}  // namespace cvo::drivers
