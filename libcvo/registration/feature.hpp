#pragma once
#include <array>
#include <cstddef>

namespace cvo::registration {

/// Appearance label ℓ(x) of a point: R, G, B in [0, 1], then the grey image's gradient (gx, gy)
/// as central differences of [0, 1] intensities (so each in [-1, 1]).
inline constexpr std::size_t kFeatureDim = 5;
using Feature = std::array<float, kFeatureDim>;

}  // namespace cvo::registration
