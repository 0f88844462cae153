#include "libcvo/registration/kernel.hpp"

namespace cvo::registration::kernel {

Isa best_isa() {
#if defined(CVO_HAVE_AVX2)
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return Isa::kAvx2;
#endif
  return Isa::kScalar;
}

PointFunction point_function(Isa isa) {
#if defined(CVO_HAVE_AVX2)
  if (isa == Isa::kAvx2 && best_isa() == Isa::kAvx2) return &point_avx2;
#endif
  (void)isa;
  return &point_scalar;
}

const char* to_string(Isa isa) { return isa == Isa::kAvx2 ? "avx2" : "scalar"; }

}  // namespace cvo::registration::kernel
