#pragma once
// A rendered sequence whose end sees its start again, so that a loop closes: 13 s of the 12 s
// orbit (390°) at 10 Hz through the textured room, half-size camera, Kinect-like depth noise (so
// that KF-CVO drifts by millimetres, which loops can remove); ~5 s to render. Written to DIR/orbit.
#include <filesystem>

#include "libcvo/sim/sequence.hpp"

namespace cvo::testing {

inline std::filesystem::path write_loop_orbit(const std::filesystem::path& dir) {
  sim::SequenceOptions options;
  options.path = sim::PathKind::orbit;
  options.frames = 130;
  options.rate_hz = 10.0;
  options.seed = 7;
  options.noise.enabled = true;
  options.render.supersample = false;
  options.intrinsics = {262.5, 262.5, 159.25, 119.25, 320, 240, 5000.0};
  const auto seq = dir / "orbit";
  sim::write_sequence(seq, options);
  return seq;
}

}  // namespace cvo::testing
