// The pair pass with AVX2 and FMA (built with -mavx2 -mfma; called only where the CPU has them).
#include <immintrin.h>

#include "batch_kernel.hpp"

namespace shapeform::core::batch {
namespace {
struct Isa : Lanes<4, Isa> {
  static V fma(V a, V b, V c) { return _mm256_fmadd_pd(a, b, c); }
  static V fnma(V a, V b, V c) { return _mm256_fnmadd_pd(a, b, c); }
  static V sqrt(V v) { return _mm256_sqrt_pd(v); }
};
}  // namespace

void pairs_avx2(const PairPass& p, std::int64_t row_begin, std::int64_t row_end) {
  PairKernel<Isa>::run(p, row_begin, row_end);
}

double fma_chains_avx2(std::int64_t iterations) { return fma_chains<Isa>(iterations); }
}  // namespace shapeform::core::batch
