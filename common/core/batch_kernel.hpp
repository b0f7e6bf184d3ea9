#pragma once
/// The pair pass of batch_pairs.hpp, written once for any vector width with GCC vector extensions.
/// Included only by the per-instruction-set files, each built with its own -m flags, which define
/// `struct Isa : Lanes<width, Isa>` with its fused multiply-add (and may replace the power).
/// Everything here has internal linkage and calls no library function, so no function compiled for
/// one instruction set can stand in for another's (the one-definition rule would let the linker pick
/// any copy of an inline function).
#include "batch_pairs.hpp"

namespace shapeform::core::batch {
namespace {

/// Vector types of W doubles (V the values, U their bits, M comparison results: all ones or zero), and
/// the power in plain vector arithmetic, for any instruction set Isa (which supplies Isa::fma).
template <int W, class Isa>
struct Lanes {
  static constexpr int kWidth = W;
  // typedef: GCC 12 drops a dependent vector_size from an alias declaration (`using`)
  typedef double V __attribute__((vector_size(8 * W)));
  typedef std::uint64_t U __attribute__((vector_size(8 * W)));
  typedef std::int64_t M __attribute__((vector_size(8 * W)));
  static_assert(sizeof(V) == 8 * W && sizeof(U) == 8 * W && sizeof(M) == 8 * W, "vector types");

  static V splat(double s) { return V{} + s; }
  static V load(const double* p) {
    V v;
    __builtin_memcpy(&v, p, sizeof v);
    return v;
  }
  static void store(double* p, V v) { __builtin_memcpy(p, &v, sizeof v); }

  /// The power's constants for one exponent, made once per pass: log2 m = s q(s^2) with
  /// s = (m - 1)/(m + 1) for m in [0.75, 1.5) (q of degree 7, near-minimax: a Chebyshev fit, relative
  /// error 2e-17), here times mbeta; 2^r for |r| <= 1/2 (degree 10, relative error 3e-16).
  struct Pow {
    V mbeta, q[8];
    explicit Pow(double mb) : mbeta(splat(mb)) {
      constexpr double c[8] = {2.8853900817779268, 0.9617966939261012, 0.5770780162897531, 0.4121985962411068,
                               0.32059761439629403, 0.2623761241235996, 0.2199728043635776, 0.22198752919751308};
      for (int k = 0; k < 8; ++k) q[k] = splat(c[k] * mb);
    }
  };

  /// u^mbeta for u >= sigma^2 (normal, finite) and u^mbeta <= about 2^1000 (batch.cpp checks
  /// sigma^-2beta), as 2^t with t = mbeta log2 u. Relative error a few 1e-16 (t is rounded about
  /// once, ulp(t) <= 1e-14 for any u the workspace allows); results below 2^-1022 are flushed to 0.
  /// Polynomials in Estrin's scheme: a short dependency chain.
  static V pow_neg(V u, const Pow& c) {
    // u = m 2^e with m in [0.75, 1.5), from the bits.
    const U b = (U)u;
    V e = (V)((b >> 52) | 0x4330000000000000ull) - 4503599627371519.0;  // unbiased exponent: - (2^52 + 1023)
    V m = (V)((b & 0x000fffffffffffffull) | 0x3ff0000000000000ull);   // in [1, 2)
    const M big = m >= 1.5;
    m = big ? m * 0.5 : m;
    e = big ? e + 1.0 : e;
    const V s = (m - 1.0) / (m + 1.0);  // m - 1 exact (Sterbenz)
    const V z = s * s, z2 = z * z;
    const V q03 = Isa::fma(Isa::fma(c.q[3], z, c.q[2]), z2, Isa::fma(c.q[1], z, c.q[0]));
    const V q47 = Isa::fma(Isa::fma(c.q[7], z, c.q[6]), z2, Isa::fma(c.q[5], z, c.q[4]));
    V t = Isa::fma(s, Isa::fma(q47, z2 * z2, q03), c.mbeta * e);
    // 2^t = 2^n 2^r with n = round(t) (the 1.5 2^52 shift rounds to nearest and leaves n in the low
    // bits), |r| <= 1/2.
    const M under = t < -1022.0;
    t = under ? splat(-1022.0) : t;
    const V k = t + 0x1.8p52;
    const V r = t - (k - 0x1.8p52);
    const V r2 = r * r, r4 = r2 * r2;
    const V p03 = Isa::fma(Isa::fma(splat(0.05550410866444772), r, splat(0.24022650695910097)), r2,
                           Isa::fma(splat(0.69314718055995), r, splat(1.0)));
    const V p47 = Isa::fma(Isa::fma(splat(1.5252657260200837e-05), r, splat(0.0001540353044173605)), r2,
                           Isa::fma(splat(0.0013333558230164974), r, splat(0.009618129107606888)));
    const V p810 = Isa::fma(splat(7.072585949269223e-09), r2,
                            Isa::fma(splat(1.0208690299958306e-07), r, splat(1.321544258792169e-06)));
    const V two_n = (V)(((U)k + 1023ull) << 52);  // n + 1023 in [1, 2046]
    return under ? V{} : Isa::fma(p810, r4 * r4, Isa::fma(p47, r4, p03)) * two_n;
  }
};

template <class Isa>
struct PairKernel {
  using V = typename Isa::V;
  using M = typename Isa::M;
  static constexpr int kW = Isa::kWidth;

  /// The pairs (i, j..j+kW-1) of one vector: j's outputs updated, i's kept in registers. Lanes at or
  /// past n (only in a row's last vector, `tail`) take no part.
  template <bool tail>
  static void block(const PairPass& p, const typename Isa::Pow& pow, std::int64_t j, V xi, V yi, V self, V& ax,
                    V& ay, V& best, V& best_j) {
    const V jv = lane() + static_cast<double>(j);
    const V dx = Isa::load(p.x + j) - xi, dy = Isa::load(p.y + j) - yi;
    V d2 = dx * dx + dy * dy;  // as the per-agent law rounds it (no FMA): the same nearest neighbours
    V w = Isa::pow_neg(p.s2 + d2, pow);
    if (tail) {
      const M valid = jv < static_cast<double>(p.n);
      w = valid ? w : V{};
      d2 = valid ? d2 : Isa::splat(__builtin_inf());
    }
    ax = Isa::fma(w, dx, ax);
    ay = Isa::fma(w, dy, ay);
    Isa::store(p.sx + j, Isa::fma(-w, dx, Isa::load(p.sx + j)));  // j sees x_i - x_j = -(dx, dy)
    Isa::store(p.sy + j, Isa::fma(-w, dy, Isa::load(p.sy + j)));
    // Rows come in ascending i and only a strictly nearer one replaces: ties keep the lowest id.
    const V jd = Isa::load(p.nd2 + j);
    const M nearer = d2 < jd;
    Isa::store(p.nd2 + j, nearer ? d2 : jd);
    Isa::store(p.nid + j, nearer ? self : Isa::load(p.nid + j));
    const M mine = d2 < best;  // per lane, j ascends: ties keep the lowest id
    best = mine ? d2 : best;
    best_j = mine ? jv : best_j;
  }

  static V lane() {
    double iota[kW];
    for (int l = 0; l < kW; ++l) iota[l] = l;
    return Isa::load(iota);
  }

  static void run(const PairPass& pass, std::int64_t row_begin, std::int64_t row_end) {
    const PairPass p = pass;  // a local copy: the stores below cannot change it, so it stays in registers
    const typename Isa::Pow pow(p.mbeta);
    for (std::int64_t i = row_begin; i < row_end; ++i) {
      const V xi = Isa::splat(p.x[i]), yi = Isa::splat(p.y[i]), self = Isa::splat(static_cast<double>(i));
      V ax{}, ay{}, best = Isa::splat(__builtin_inf()), best_j = Isa::splat(-1.0);
      std::int64_t j = i + 1;
      for (; j + kW <= p.n; j += kW) block<false>(p, pow, j, xi, yi, self, ax, ay, best, best_j);
      if (j < p.n) block<true>(p, pow, j, xi, yi, self, ax, ay, best, best_j);
      // i's candidates so far have lower ids than any lane's, so they win ties; among lanes the lowest id.
      double sx = 0.0, sy = 0.0, bd = p.nd2[i], bj = p.nid[i];
      double lx[kW] = {}, ly[kW] = {}, ld[kW] = {}, lj[kW] = {};  // lanes (a dependent vector type takes no subscript)
      Isa::store(lx, ax), Isa::store(ly, ay), Isa::store(ld, best), Isa::store(lj, best_j);
      for (int l = 0; l < kW; ++l) {
        sx += lx[l];
        sy += ly[l];
        if (ld[l] < bd || (ld[l] == bd && bj > static_cast<double>(i) && lj[l] < bj)) {
          bd = ld[l];
          bj = lj[l];
        }
      }
      p.sx[i] += sx;
      p.sy[i] += sy;
      p.nd2[i] = bd;
      p.nid[i] = bj;
    }
  }
};

}  // namespace
}  // namespace shapeform::core::batch
