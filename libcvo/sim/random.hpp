#pragma once
// Counter-based randomness: every random number is a pure hash of (seed, what it is for), so a
// texture value or a pixel's noise never depends on evaluation order. That keeps the renderer
// deterministic by construction and lets any pixel be rendered on its own.
#include <cmath>
#include <cstdint>
#include <numbers>

namespace cvo::sim {

/// SplitMix64 finaliser: a bijective 64-bit mixer with full avalanche.
constexpr std::uint64_t mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// Hash of a key sequence; hash(a, b) != hash(b, a).
constexpr std::uint64_t hash(std::uint64_t a, std::uint64_t b) { return mix64(a ^ mix64(b)); }
constexpr std::uint64_t hash(std::uint64_t a, std::uint64_t b, std::uint64_t c) { return hash(hash(a, b), c); }
constexpr std::uint64_t hash(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d) {
  return hash(hash(a, b, c), d);
}

/// Hash of an integer lattice point: one mixing round, for the hot loop of value noise.
constexpr std::uint64_t lattice_hash(std::uint64_t key, std::uint64_t ix, std::uint64_t iy) {
  return mix64(key + ix * 0xd1b54a32d192ed03ULL + iy * 0xabc98388fb8fac03ULL);
}

/// Uniform in [0, 1) from the top 53 bits.
/// (Converted through int64: x86-64 has no direct unsigned 64-bit conversion, it would branch.)
constexpr double to_unit(std::uint64_t h) {
  return static_cast<double>(static_cast<std::int64_t>(h >> 11)) * 0x1.0p-53;
}

/// Standard normal sample (Box-Muller) from one key.
inline double gaussian(std::uint64_t key) {
  const double u1 = 1.0 - to_unit(mix64(key));  // (0, 1]: log stays finite
  const double u2 = to_unit(mix64(key ^ 0x5851f42d4c957f2dULL));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

/// Tiny sequential generator (a SplitMix64 stream): draw i is mix64(seed + i * odd constant).
class Draws {
 public:
  explicit Draws(std::uint64_t seed) : seed_(seed) {}
  double uniform() { return to_unit(mix64(seed_ + 0xda942042e4dd58b5ULL * counter_++)); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  int integer(int lo, int hi_inclusive) {
    return lo + static_cast<int>(uniform() * static_cast<double>(hi_inclusive - lo + 1));
  }

 private:
  std::uint64_t seed_;
  std::uint64_t counter_ = 0;
};

}  // namespace cvo::sim
