// The pair pass with AVX-512 F and DQ (built with -mavx512f -mavx512dq; called only where the CPU has them).
#include <immintrin.h>

#include "batch_kernel.hpp"

// GCC 12's AVX-512 intrinsics start their results from _mm512_undefined_pd(), which
// -Wmaybe-uninitialized takes for a read of an uninitialised value once inlined here.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace shapeform::core::batch {
namespace {
struct Isa : Lanes<8, Isa> {
  static V fma(V a, V b, V c) { return _mm512_fmadd_pd(a, b, c); }    // a b + c, rounded once
  static V fnma(V a, V b, V c) { return _mm512_fnmadd_pd(a, b, c); }  // c - a b, rounded once
  static V sqrt(V v) { return _mm512_sqrt_pd(v); }
  static V splat(double s) { return _mm512_set1_pd(s); }  // a broadcast, of memory where it can

  /// Constants of pow_neg for one exponent: 16-entry tables (two registers each, read with one
  /// permute) and polynomials near-minimax on the reduced ranges (Chebyshev fits).
  struct Pow {
    double mbeta, q[7], p[6];  // scalars, broadcast where used: no register held for them
    V inv[2], mlog[2], exp[2];
    explicit Pow(double mb) : mbeta(mb) {
      // log2(1 + r) / r for |r| <= 0.0304, degree 6 (relative error 5e-14 on a term below 0.045).
      constexpr double qc[7] = {1.4426950408889634,   -0.7213475204597833, 0.4808983469765897,
                                -0.36067362695320027, 0.28853888971320746, -0.24073929544571335,
                                0.2063571831318346};
      // 2^r for |r| <= 1/32, degree 5 (relative error 5e-15; degree 6, 8e-18, took 4 % longer per pair).
      constexpr double pc[6] = {1.0000000000000044, 0.6931471805599457,   0.24022650687646874,
                                0.0555041086566393, 0.009618354747407538, 0.0013333781576784268};
      // 1 / (1 + (j + 1/2)/16), its -log2 (here times mbeta), and 2^(j/16), j = 0..15.
      constexpr double inv_c[16] = {
          0.9696969696969697, 0.9142857142857143, 0.8648648648648649, 0.8205128205128205,
          0.7804878048780488, 0.7441860465116279, 0.7111111111111111, 0.6808510638297872,
          0.6530612244897959, 0.6274509803921569, 0.6037735849056604, 0.5818181818181818,
          0.5614035087719298, 0.5423728813559322, 0.5245901639344263, 0.5079365079365079};
      constexpr double log_c[16] = {
          0.044394119358453395, 0.1292830169449665,  0.2094533656289497,  0.28540221886224837,
          0.3575520046180836,   0.42626475470209796, 0.49185309632967467, 0.5545888516776374,
          0.6147098441152083,   0.6724253419714956,  0.7279204545631992,  0.7813597135246597,
          0.8328900141647417,   0.8826430493618412,  0.9307373375628862,  0.9772799234999165};
      constexpr double exp_c[16] = {1.0,
                                    1.0442737824274138,
                                    1.0905077326652577,
                                    1.1387886347566916,
                                    1.189207115002721,
                                    1.241857812073484,
                                    1.2968395546510096,
                                    1.3542555469368927,
                                    1.4142135623730951,
                                    1.4768261459394993,
                                    1.5422108254079407,
                                    1.6104903319492543,
                                    1.681792830507429,
                                    1.7562521603732995,
                                    1.8340080864093424,
                                    1.9152065613971474};
      for (int k = 0; k < 7; ++k) q[k] = qc[k] * mb;
      for (int k = 0; k < 6; ++k) p[k] = pc[k];
      for (int h = 0; h < 2; ++h)
        inv[h] = load(inv_c + 8 * h), mlog[h] = load(log_c + 8 * h) * mb, exp[h] = load(exp_c + 8 * h);
    }
  };

  /// Lanes::pow_neg's contract with table-driven reductions, which AVX-512 reads in one instruction
  /// each (getmant, getexp, a two-register permute, roundscale, scalef): about a third fewer operations
  /// and no division on the dependency chain. Relative error below 1e-14 (t = mbeta log2 u is rounded
  /// about twice); below 2^-1022 gradual underflow to 0, as std::pow.
  static V pow_neg(V u, const Pow& c) { return pow_exp(pow_log(u, c), c); }
  /// pow_neg's first half: t = mbeta log2 u.
  static V pow_log(V u, const Pow& c) {
    // u = m 2^e, m in [1, 2); m = (1 + r) / inv_j for the 16th j of [1, 2) that holds m, |r| <= 0.0304.
    const V m = _mm512_getmant_pd(u, _MM_MANT_NORM_1_2, _MM_MANT_SIGN_src);
    const V e = _mm512_getexp_pd(u);
    const __m512i j = _mm512_srli_epi64(_mm512_castpd_si512(m), 48);  // the permute reads bits 3:0
    const V r = fma(m, _mm512_permutex2var_pd(c.inv[0], j, c.inv[1]), splat(-1.0));
    const V r2 = r * r;
    const V q03 = fma(fma(splat(c.q[3]), r, splat(c.q[2])), r2, fma(splat(c.q[1]), r, splat(c.q[0])));
    const V q46 = fma(splat(c.q[6]), r2, fma(splat(c.q[5]), r, splat(c.q[4])));
    // t = mbeta (e + log2 m) = mbeta e - mbeta log2 inv_j + r mbeta q(r)
    return fma(r, fma(q46, r2 * r2, q03),
               fma(splat(c.mbeta), e, _mm512_permutex2var_pd(c.mlog[0], j, c.mlog[1])));
  }
  /// pow_neg's second half: 2^t.
  static V pow_exp(V t, const Pow& c) {
    // 2^t = 2^floor(n) 2^(k/16) 2^f: n = t to the nearest 16th, k = 16 n mod 16, f = t - n, |f| <= 1/32.
    const V n = _mm512_roundscale_pd(t, (4 << 4) | _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
    const V f = t - n;                                    // exact
    const __m512i k = _mm512_castpd_si512(n + 0x1.8p48);  // 16 n in the low bits
    const V f2 = f * f;
    const V p03 = fma(fma(splat(c.p[3]), f, splat(c.p[2])), f2, fma(splat(c.p[1]), f, splat(c.p[0])));
    return _mm512_scalef_pd(
        fma(fma(splat(c.p[5]), f, splat(c.p[4])), f2 * f2, p03) * _mm512_permutex2var_pd(c.exp[0], k, c.exp[1]), n);
  }
};
}  // namespace

void pairs_avx512(const PairPass& p, std::int64_t row_begin, std::int64_t row_end) {
  PairKernel<Isa>::run(p, row_begin, row_end);
}

double fma_chains_avx512(std::int64_t iterations) { return fma_chains<Isa>(iterations); }
}  // namespace shapeform::core::batch
