#include "libcvo/sim/texture.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "libcvo/sim/random.hpp"

namespace cvo::sim {
namespace {

// Domain-separation tags so the noise lattice and the shape draws never share hashes.
constexpr std::uint64_t kNoiseTag = 0x6e6f697365ULL;    // "noise"
constexpr std::uint64_t kPatchTag = 0x7061746368ULL;    // "patch"
constexpr std::uint64_t kSpeckleTag = 0x737065636bULL;  // "speck"

double smooth(double u) { return u * u * (3.0 - 2.0 * u); }

// floor() without a libm call (baseline x86-64 has no SSE4.1 round instruction); the texture
// coordinates are far inside the int64 range.
double fast_floor(double x) {
  const auto truncated = static_cast<double>(static_cast<std::int64_t>(x));
  return truncated > x ? truncated - 1.0 : truncated;
}

std::uint64_t lattice_key(double v) { return static_cast<std::uint64_t>(static_cast<std::int64_t>(v)); }

// The two 32-bit halves of a hash as numbers in [0, 1).
double low_unit(std::uint64_t h) { return static_cast<double>(static_cast<std::uint32_t>(h)) * 0x1.0p-32; }
double high_unit(std::uint64_t h) { return static_cast<double>(static_cast<std::uint32_t>(h >> 32)) * 0x1.0p-32; }

// Two noise channels; plain doubles (GCC 12 reports false maybe-uninitialized warnings for
// Eigen::Vector2d temporaries here).
struct Noise2 {
  double a = 0.5, b = 0.5;
};

// Two independent value-noise channels in [0, 1] from one lattice: the low and high 32 bits of
// each corner hash, bilinearly blended with smoothstep weights.
Noise2 value_noise(std::uint64_t key, double x, double y) {
  const double fx = fast_floor(x), fy = fast_floor(y);
  const double ux = smooth(x - fx), uy = smooth(y - fy);
  const std::uint64_t ix = lattice_key(fx), iy = lattice_key(fy);
  const double w[4] = {(1 - ux) * (1 - uy), ux * (1 - uy), (1 - ux) * uy, ux * uy};
  Noise2 n{0, 0};
  for (std::uint64_t c = 0; c < 4; ++c) {
    const std::uint64_t h = lattice_hash(key, ix + (c & 1), iy + (c >> 1));
    n.a += w[c] * low_unit(h);
    n.b += w[c] * high_unit(h);
  }
  return n;
}

// Fractal sum; each octave is rotated by a further 37 degrees so lattice axes do not line up.
Noise2 fractal_noise(const Texture& tex, double s, double t) {
  const double c = std::cos(0.6458), sn = std::sin(0.6458);
  Noise2 sum{0, 0};
  double weight = 1.0, total = 0.0, f = tex.base_frequency;
  double x = s, y = t;
  for (int k = 0; k < tex.octaves; ++k) {
    const Noise2 n = value_noise(mix64(tex.seed ^ kNoiseTag ^ static_cast<std::uint64_t>(k)), x * f, y * f);
    sum.a += weight * n.a;
    sum.b += weight * n.b;
    total += weight;
    weight *= tex.gain;
    f *= 2.0;
    const double xr = c * x - sn * y;
    y = sn * x + c * y;
    x = xr;
  }
  return {sum.a / total, sum.b / total};
}

Eigen::Vector3d random_colour(Draws& d) { return hsv_to_rgb(d.uniform(), d.uniform(0.25, 0.9), d.uniform(0.2, 0.95)); }

// The colour of the patch of the cell holding (s, t), if (s, t) lies on it. Draws that only
// matter inside the shape come last, so most evaluations stop early.
std::optional<Eigen::Vector3d> patch_at(const Texture& tex, double s, double t) {
  const double gx = s / tex.patch_cell, gy = t / tex.patch_cell;
  const double cx = fast_floor(gx), cy = fast_floor(gy);
  const double u = gx - cx, v = gy - cy;  // position in the cell, [0, 1)
  Draws d(lattice_hash(tex.seed ^ kPatchTag, lattice_key(cx), lattice_key(cy)));
  if (d.uniform() >= tex.patch_probability) return std::nullopt;
  const int shape = d.integer(0, 3);
  const double hu = d.uniform(0.08, 0.3), hv = d.uniform(0.08, 0.3);  // half sizes, cell units
  constexpr double kMargin = 0.04;
  const double du = u - d.uniform(hu + kMargin, 1.0 - hu - kMargin);
  const double dv = v - d.uniform(hv + kMargin, 1.0 - hv - kMargin);
  const bool inside =
      shape == 0 ? (du / hu) * (du / hu) + (dv / hv) * (dv / hv) <= 1.0 : std::abs(du) <= hu && std::abs(dv) <= hv;
  if (!inside) return std::nullopt;
  const Eigen::Vector3d first = random_colour(d);
  if (shape <= 1) return first;  // plain ellipse or rectangle
  const Eigen::Vector3d second = random_colour(d);
  const double period = d.uniform(0.03, 0.1) / tex.patch_cell;  // 3-10 cm, in cell units
  if (shape == 2) {                                             // stripes
    const double x = (d.uniform() < 0.5 ? du : dv) / period;
    return x - fast_floor(x) < 0.5 ? first : second;
  }
  const auto parity = static_cast<std::int64_t>(fast_floor(du / period) + fast_floor(dv / period));  // checks
  return (parity & 1) != 0 ? first : second;
}

std::optional<Eigen::Vector3d> speckle_at(const Texture& tex, double s, double t) {
  const double gx = s / tex.speckle_cell, gy = t / tex.speckle_cell;
  const double cx = fast_floor(gx), cy = fast_floor(gy);
  Draws d(lattice_hash(tex.seed ^ kSpeckleTag, lattice_key(cx), lattice_key(cy)));
  if (d.uniform() >= tex.speckle_probability) return std::nullopt;
  const double r = d.uniform(0.1, 0.3);  // radius, cell units
  const double du = gx - cx - d.uniform(r, 1.0 - r), dv = gy - cy - d.uniform(r, 1.0 - r);
  if (du * du + dv * dv > r * r) return std::nullopt;
  return random_colour(d);
}

}  // namespace

Eigen::Vector3d hsv_to_rgb(double h, double s, double v) {
  h = (h - std::floor(h)) * 6.0;
  const int sector = std::min(static_cast<int>(h), 5);
  const double f = h - sector;
  const double p = v * (1 - s), q = v * (1 - s * f), r = v * (1 - s * (1 - f));
  switch (sector) {
    case 0: return {v, r, p};
    case 1: return {q, v, p};
    case 2: return {p, v, r};
    case 3: return {p, q, v};
    case 4: return {r, p, v};
    default: return {v, p, q};
  }
}

Texture flat_texture(const Eigen::Vector3d& rgb) {
  Texture tex;
  tex.base = tex.tint = rgb;
  return tex;
}

Texture random_flat_texture(std::uint64_t seed) {
  Draws d(seed);
  return flat_texture(hsv_to_rgb(d.uniform(), d.uniform(0.2, 0.6), d.uniform(0.45, 0.8)));
}

Texture random_texture(std::uint64_t seed) {
  Draws d(seed);
  Texture tex;
  tex.seed = mix64(seed ^ 0x7465787475726573ULL);
  const double hue = d.uniform();
  tex.base = hsv_to_rgb(hue, d.uniform(0.2, 0.7), d.uniform(0.45, 0.75));
  tex.tint = hsv_to_rgb(hue + d.uniform(0.15, 0.5), d.uniform(0.2, 0.7), d.uniform(0.35, 0.8));
  tex.base_frequency = d.uniform(2.0, 3.0);
  tex.octaves = 6;
  tex.gain = 1.0;
  tex.contrast = d.uniform(0.5, 0.6);
  tex.patch_cell = d.uniform(0.7, 1.2);
  tex.patch_probability = 0.8;
  tex.speckle_cell = d.uniform(0.08, 0.12);
  tex.speckle_probability = 0.75;
  return tex;
}

Eigen::Vector3d albedo(const Texture& tex, double s, double t) {
  if (tex.octaves <= 0 && tex.patch_probability <= 0 && tex.speckle_probability <= 0) return tex.base;
  const Noise2 n = tex.octaves > 0 ? fractal_noise(tex, s, t) : Noise2{};
  // Stretch both channels: fractal noise clusters around 1/2.
  const double blend = std::clamp(0.5 + 2.5 * (n.b - 0.5), 0.0, 1.0);
  Eigen::Vector3d rgb = (1 - blend) * tex.base + blend * tex.tint;
  if (tex.patch_probability > 0)
    if (const auto patch = patch_at(tex, s, t)) rgb = *patch;
  if (tex.speckle_probability > 0)
    if (const auto speckle = speckle_at(tex, s, t)) rgb = *speckle;
  // Lighten towards white or darken towards black: the same visible contrast on dark and light
  // colours (a plain gain would leave dark surfaces nearly flat).
  const double x = tex.contrast * std::clamp(3.0 * (n.a - 0.5), -1.0, 1.0);
  rgb = x > 0 ? (rgb + x * (Eigen::Vector3d::Ones() - rgb)).eval() : ((1.0 + x) * rgb).eval();
  return rgb.cwiseMax(0.02).cwiseMin(0.98);
}

}  // namespace cvo::sim
