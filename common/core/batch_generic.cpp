// The pair pass for any CPU: two-lane vectors (SSE2 on x86-64), no FMA.
#include "batch_kernel.hpp"

namespace shapeform::core::batch {
namespace {
struct Isa : Lanes<2, Isa> {
  static V fma(V a, V b, V c) { return a * b + c; }
  static V fnma(V a, V b, V c) { return c - a * b; }
};
}  // namespace

void pairs_generic(const PairPass& p, std::int64_t row_begin, std::int64_t row_end) {
  PairKernel<Isa>::run(p, row_begin, row_end);
}

double fma_chains_generic(std::int64_t iterations) { return fma_chains<Isa>(iterations); }
}  // namespace shapeform::core::batch
