#include "libcvo/registration/kernel.hpp"

namespace cvo::registration::kernel {

Isa best_isa() {
#if defined(CVO_HAVE_AVX2)
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return Isa::kAvx2;
#endif
#if defined(CVO_HAVE_NEON)
  return Isa::kNeon;  // Advanced SIMD is mandatory in ARMv8-A: no runtime check needed
#endif
  return Isa::kScalar;
}

PointFunction point_function(Isa isa) {
#if defined(CVO_HAVE_AVX2)
  if (isa == Isa::kAvx2 && best_isa() == Isa::kAvx2) return &point_avx2;
#endif
#if defined(CVO_HAVE_NEON)
  if (isa == Isa::kNeon) return &point_neon;
#endif
  (void)isa;
  return &point_scalar;
}

CollectFunction collect_function(Isa isa) {
#if defined(CVO_HAVE_AVX2)
  if (isa == Isa::kAvx2 && best_isa() == Isa::kAvx2) return &collect_avx2;
#endif
  (void)isa;
  return &collect_scalar;
}

CandidateFunction candidate_function(Isa isa) {
#if defined(CVO_HAVE_AVX2)
  if (isa == Isa::kAvx2 && best_isa() == Isa::kAvx2) return &candidates_avx2;
#endif
  (void)isa;
  return &candidates_scalar;
}

const char* to_string(Isa isa) {
  switch (isa) {
    case Isa::kAvx2: return "avx2";
    case Isa::kNeon: return "neon";
    case Isa::kScalar: break;
  }
  return "scalar";
}

}  // namespace cvo::registration::kernel
