#pragma once
// Procedural surface textures, evaluated in surface coordinates (s, t) in metres, so appearance is
// glued to the geometry and moves exactly with the viewpoint (brightness constancy holds).
//
//   x = c clamp(3 (n_a(s, t) - 1/2), -1, 1)
//   albedo(s, t) = layer + x (1 - layer)  if x > 0 (towards white),  (1 + x) layer  otherwise
//
// n_a, n_b are two independent channels of fractal value noise: octaves at f0, 2 f0, 4 f0, ...
// cycles per metre with amplitude ratio `gain` per octave, normalised to [0, 1]; c is the
// contrast. With f0 ~ 2/m, six octaves and gain 0.8 the spectrum is close to pink: clouds at
// room scale and grain down to ~1.5 cm, so there is image gradient at every viewing distance.
// layer is, bottom up:
//   * the background: base colour blended towards a tint colour by n_b;
//   * patches: at most one per cell of a patch_cell grid - an ellipse, a rectangle, a stripe band
//     or a checkerboard in one or two random colours - lying wholly inside its cell;
//   * speckles: at most one small random-coloured disk per cell of a (finer) speckle_cell grid.
// Shapes never leave their cell, so a point only looks at its own cells: O(1) per evaluation, and
// planes of any size work. Shape edges give corners and strong gradients for point selectors.
// Everything is a pure function of the seed.
#include <cstdint>

#include <Eigen/Core>

namespace cvo::sim {

struct Texture {
  std::uint64_t seed = 0;
  Eigen::Vector3d base{0.5, 0.5, 0.5};  // linear RGB albedo in [0, 1]
  Eigen::Vector3d tint{0.5, 0.5, 0.5};
  double base_frequency = 2.0;  // f0, cycles per metre
  int octaves = 0;              // 0: no noise
  double gain = 0.8;
  double contrast = 0.0;    // c above
  double patch_cell = 1.0;  // metres
  double patch_probability = 0.0;
  double speckle_cell = 0.15;  // metres
  double speckle_probability = 0.0;
};

/// One flat colour: no noise, no patches, no speckles.
Texture flat_texture(const Eigen::Vector3d& rgb);
/// A random flat colour of medium brightness, distinct per seed.
Texture random_flat_texture(std::uint64_t seed);
/// A random rich texture: colours, noise frequency, patch and speckle grids drawn from the seed.
Texture random_texture(std::uint64_t seed);

/// Albedo (RGB in [0, 1]) at surface coordinates (s, t) metres.
Eigen::Vector3d albedo(const Texture& texture, double s, double t);

/// HSV (all in [0, 1]; hue wraps) to RGB.
Eigen::Vector3d hsv_to_rgb(double h, double s, double v);

}  // namespace cvo::sim
