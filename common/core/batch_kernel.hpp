#pragma once
/// The pair pass of batch_pairs.hpp, written once for any vector width with GCC vector extensions.
/// Included only by the per-instruction-set files, each built with its own -m flags, which define
/// `struct Isa : Lanes<width, Isa>` with its fused multiply-adds fma (a b + c) and fnma (c - a b), and
/// may replace the power.
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
  static V sqrt(V v) {  // lane by lane: the generic vectors have no square root
    double l[W] = {};
    store(l, v);
    for (double& x : l) x = __builtin_sqrt(x);
    return load(l);
  }

  /// The power's constants for one exponent, made once per pass: log2 m = s q(s^2) with
  /// s = (m - 1)/(m + 1) for m in [0.75, 1.5) (q of degree 7, near-minimax: a Chebyshev fit, relative
  /// error 2e-17), here times mbeta; 2^r for |r| <= 1/2 (degree 10, relative error 3e-16).
  struct Pow {
    V mbeta, q[8];
    explicit Pow(double mb) : mbeta(splat(mb)) {
      constexpr double c[8] = {2.8853900817779268, 0.9617966939261012,  0.5770780162897531,
                               0.4121985962411068, 0.32059761439629403, 0.2623761241235996,
                               0.2199728043635776, 0.22198752919751308};
      for (int k = 0; k < 8; ++k) q[k] = splat(c[k] * mb);
    }
  };

  /// u^mbeta for u >= sigma^2 (normal, finite) and u^mbeta <= about 2^1000 (batch.cpp checks
  /// sigma^-2beta), as 2^t with t = mbeta log2 u. Relative error a few 1e-16 (t is rounded about
  /// once, ulp(t) <= 1e-14 for any u the workspace allows); results below 2^-1022 are flushed to 0.
  /// Polynomials in Estrin's scheme: a short dependency chain.
  static V pow_neg(V u, const Pow& c) { return pow_exp(pow_log(u, c), c); }
  /// pow_neg's first half: t = mbeta log2 u.
  static V pow_log(V u, const Pow& c) {
    // u = m 2^e with m in [0.75, 1.5), from the bits.
    const U b = (U)u;
    V e = (V)((b >> 52) | 0x4330000000000000ull) - 4503599627371519.0;  // unbiased exponent: - (2^52 + 1023)
    V m = (V)((b & 0x000fffffffffffffull) | 0x3ff0000000000000ull);     // in [1, 2)
    const M big = m >= 1.5;
    m = big ? m * 0.5 : m;
    e = big ? e + 1.0 : e;
    const V s = (m - 1.0) / (m + 1.0);  // m - 1 exact (Sterbenz)
    const V z = s * s, z2 = z * z;
    const V q03 = Isa::fma(Isa::fma(c.q[3], z, c.q[2]), z2, Isa::fma(c.q[1], z, c.q[0]));
    const V q47 = Isa::fma(Isa::fma(c.q[7], z, c.q[6]), z2, Isa::fma(c.q[5], z, c.q[4]));
    return Isa::fma(s, Isa::fma(q47, z2 * z2, q03), c.mbeta * e);
  }
  /// pow_neg's second half: 2^t.
  static V pow_exp(V t, const Pow&) {
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

  /// The pair weight u^-beta, u = sigma^2 + d^2, in two halves: head(u) and tail(head(u)), each applied
  /// to a whole tile in its own sweep (rows()). Isa::pow_neg for any beta: its logarithm, then its
  /// exponential.
  struct AnyBeta {
    static constexpr bool kSweeps = true;  ///< its two halves in sweeps of their own (rows())
    typename Isa::Pow c;
    V head(V u) const { return Isa::pow_log(u, c); }
    V tail(V t) const { return Isa::pow_exp(t, c); }
  };
  /// ... and for beta = k/2, k = 1..4, from a square root, a product and a division, each correctly
  /// rounded: within 2 ulp of std::pow and a quarter of the time (beta = 1: 1/u). For beta = 0 the
  /// weight is 1, exactly as std::pow gives it: the pass without a weight to compute, which is also
  /// what the benchmark's beta = 0 rows measure (the pass's cost apart from the weight).
  template <int k>
  struct HalfBeta {
    static constexpr bool kSweeps = false;  ///< in one pass with the rest (rows())
    V tail(V w) const { return w; }
    V head(V u) const {
      if constexpr (k == 0) {
        (void)u;
        return Isa::splat(1.0);
      }
      if constexpr (k == 1) return 1.0 / Isa::sqrt(u);
      if constexpr (k == 2) return 1.0 / u;
      if constexpr (k == 3) return 1.0 / (u * Isa::sqrt(u));
      return 1.0 / (u * u);
    }
  };

  /// R rows' running state: their agents' coordinates and index, and per lane the sums and the
  /// nearest partner so far.
  template <int R>
  struct Rows {
    V x[R], y[R], self[R], ax[R], ay[R], best[R], best_j[R];
  };

  /// Row r's pairs with one vector of agents j: the nearest-neighbour bookkeeping of both sides (jd, jid:
  /// j's). Rows come in ascending id and only a strictly nearer one replaces: ties keep the lowest id.
  template <int R>
  static void nearest(Rows<R>& rs, int r, V d2, V jv, V& jd, V& jid) {
    const M nearer = d2 < jd;
    jd = nearer ? d2 : jd;
    jid = nearer ? rs.self[r] : jid;
    const M mine = d2 < rs.best[r];  // per lane, j ascends: ties keep the lowest id
    rs.best[r] = mine ? d2 : rs.best[r];
    rs.best_j[r] = mine ? jv : rs.best_j[r];
  }
  /// ... and their weights w into both sides' sums (sx, sy: j's).
  template <int R>
  static void add_sums(Rows<R>& rs, int r, V w, V dx, V dy, V& sx, V& sy) {
    rs.ax[r] = Isa::fma(w, dx, rs.ax[r]);
    rs.ay[r] = Isa::fma(w, dy, rs.ay[r]);
    sx = Isa::fnma(w, dx, sx);  // j sees x_i - x_j = -(dx, dy)
    sy = Isa::fnma(w, dy, sy);
  }

  /// The pairs (rows' agent, j + lane) of one vector for R rows at once (consecutive agents i,
  /// i + 1, ... all below j + lane; jv: the lanes' j as doubles): j's outputs read and written once for
  /// all R, each row's kept in registers. With `tail`, only lanes in [begin, end) take part (the others'
  /// outputs are written back unchanged).
  template <int R, bool tail, class Weight>
  static void block(const PairPass& p, const Weight& weight, std::int64_t j, V jv, double end, Rows<R>& rs,
                    double begin = 0.0) {
    const V xj = Isa::load(p.x + j), yj = Isa::load(p.y + j);
    V sx = Isa::load(p.sx + j), sy = Isa::load(p.sy + j), jd = Isa::load(p.nd2 + j),
      jid = Isa::load(p.nid + j);
#pragma GCC unroll 4
    for (int r = 0; r < R; ++r) {
      const V dx = xj - rs.x[r], dy = yj - rs.y[r];
      V d2 = dx * dx + dy * dy;  // as the per-agent law rounds it (no FMA): the same nearest neighbours
      V w = weight.tail(weight.head(p.s2 + d2));
      if (tail) {
        const M valid = (jv >= begin) & (jv < end);
        w = valid ? w : V{};
        d2 = valid ? d2 : Isa::splat(__builtin_inf());
      }
      add_sums(rs, r, w, dx, dy, sx, sy);
      nearest(rs, r, d2, jv, jd, jid);
    }
    Isa::store(p.sx + j, sx);
    Isa::store(p.sy + j, sy);
    Isa::store(p.nd2 + j, jd);
    Isa::store(p.nid + j, jid);
  }

  static V lane() {
    double iota[kW];
    for (int l = 0; l < kW; ++l) iota[l] = l;
    return Isa::load(iota);
  }

  /// Rows i .. i + R - 1 against every j from `from` (> i + R - 1) to n. Blocks start at multiples of
  /// kW, so that with PairPass's arrays aligned no vector read or written crosses a cache line; the
  /// block holding `from` counts its lanes from there. Whole blocks go in tiles of kTile agents j, in
  /// three sweeps over p.scratch (R weights' arguments per j): distances and nearest neighbours, then
  /// the weights' heads, then their tails and the sums. Each sweep keeps its constants in registers
  /// and its dependency chains short: the heads' and the tails' sweeps run at about the rate of their
  /// multiply-adds (docs/BENCHMARKS.md, Simulator). The values and the order of the sums are those of
  /// block.
  template <int R, class Weight>
  static void rows(const PairPass& p, const Weight& weight, Rows<R>& rs, std::int64_t from) {
    constexpr std::int64_t kTile = kScratch / R;
    std::int64_t j = from / kW * kW;
    V jv = lane() + static_cast<double>(j);
    if (j < from) {
      block<R, true>(p, weight, j, jv, static_cast<double>(p.n), rs, static_cast<double>(from));
      j += kW, jv += static_cast<double>(kW);
    }
    const std::int64_t whole = j + (p.n > j ? (p.n - j) / kW * kW : 0);
    if constexpr (Weight::kSweeps) {
      while (j < whole) {
        const std::int64_t end = whole - j < kTile ? whole : j + kTile;
        near_sweep<R>(p, j, end, jv, rs);
        head_sweep(weight, p.scratch, (end - j) * R);
        tail_sweep<R>(p, weight, j, end, rs);
        jv += static_cast<double>(end - j);
        j = end;
      }
    } else {
      // A weight of a square root or a division: in one pass with the distances and sums, whose work
      // then overlaps the divider's (in sweeps, beta = 1/2 took half as long again).
      Rows<R> local = rs;  // copies nothing stored below can alias: they stay in registers
      const Weight w = weight;
      for (; j < whole; j += kW, jv += static_cast<double>(kW)) block<R, false>(p, w, j, jv, 0.0, local);
      rs = local;
    }
    if (j < p.n) block<R, true>(p, weight, j, jv, static_cast<double>(p.n), rs);
  }

  /// The first sweep: each pair's squared distance, as block rounds it, and the nearest-neighbour
  /// bookkeeping; sigma^2 + d^2 into the scratch.
  template <int R>
  static void near_sweep(const PairPass& p, std::int64_t j, std::int64_t end, V jv, Rows<R>& rows) {
    Rows<R> rs = rows;  // a copy nothing stored below can alias: it stays in registers
    const V s2 = Isa::splat(p.s2);
    double* u = p.scratch;
    for (; j < end; j += kW, jv += static_cast<double>(kW), u += R * kW) {
      const V xj = Isa::load(p.x + j), yj = Isa::load(p.y + j);
      V jd = Isa::load(p.nd2 + j), jid = Isa::load(p.nid + j);
#pragma GCC unroll 4
      for (int r = 0; r < R; ++r) {
        const V dx = xj - rs.x[r], dy = yj - rs.y[r];
        const V d2 = dx * dx + dy * dy;  // as the per-agent law rounds it (no FMA): the same nearest neighbours
        Isa::store(u + r * kW, s2 + d2);
        nearest(rs, r, d2, jv, jd, jid);
      }
      Isa::store(p.nd2 + j, jd);
      Isa::store(p.nid + j, jid);
    }
    rows = rs;
  }

  /// The second sweep: the weights' heads, in place (a copy of the weight's constants: nothing the
  /// sweep stores can change them, so they stay in registers).
  template <class Weight>
  static void head_sweep(const Weight& weight, double* u, std::int64_t count) {
    const Weight w = weight;
    std::int64_t k = 0;
    for (; k + 2 * kW <= count; k += 2 * kW) {  // two independent chains per iteration
      Isa::store(u + k, w.head(Isa::load(u + k)));
      Isa::store(u + k + kW, w.head(Isa::load(u + k + kW)));
    }
    if (k < count) Isa::store(u + k, w.head(Isa::load(u + k)));  // count is a multiple of kW
  }

  /// The third sweep: the weights' tails and the sums, the differences computed again (the same values).
  template <int R, class Weight>
  static void tail_sweep(const PairPass& p, const Weight& weight, std::int64_t j, std::int64_t end, Rows<R>& rows) {
    Rows<R> rs = rows;  // copies, as in near_sweep
    const Weight w8 = weight;
    const double* h = p.scratch;
    for (; j < end; j += kW, h += R * kW) {
      const V xj = Isa::load(p.x + j), yj = Isa::load(p.y + j);
      V sx = Isa::load(p.sx + j), sy = Isa::load(p.sy + j);
#pragma GCC unroll 4
      for (int r = 0; r < R; ++r) {
        const V dx = xj - rs.x[r], dy = yj - rs.y[r];
        add_sums(rs, r, w8.tail(Isa::load(h + r * kW)), dx, dy, sx, sy);
      }
      Isa::store(p.sx + j, sx);
      Isa::store(p.sy + j, sy);
    }
    rows = rs;
  }

  /// Adds row i's lanes to agent i's outputs. i's candidates so far have lower ids than any lane's,
  /// so they win ties; among lanes the lowest id.
  template <int R>
  static void finish(const PairPass& p, const Rows<R>& rs, int r, std::int64_t i) {
    double sx = 0.0, sy = 0.0, bd = p.nd2[i], bj = p.nid[i];
    double lx[kW] = {}, ly[kW] = {}, ld[kW] = {},
           lj[kW] = {};  // lanes (a dependent vector type takes no subscript)
    Isa::store(lx, rs.ax[r]), Isa::store(ly, rs.ay[r]), Isa::store(ld, rs.best[r]),
        Isa::store(lj, rs.best_j[r]);
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

  template <int R>
  static void start(const PairPass& p, Rows<R>& rs, std::int64_t i) {
    for (int r = 0; r < R; ++r) {
      rs.x[r] = Isa::splat(p.x[i + r]), rs.y[r] = Isa::splat(p.y[i + r]);
      rs.self[r] = Isa::splat(static_cast<double>(i + r));
      rs.ax[r] = rs.ay[r] = V{};
      rs.best[r] = Isa::splat(__builtin_inf()), rs.best_j[r] = Isa::splat(-1.0);
    }
  }

  /// Rows in groups of kRows: j's loads and stores shared by the group, and kRows independent
  /// dependency chains per vector. Two measured fastest with earlier forms of the pass (AVX-512,
  /// N = 1000: 1.03, 0.94, 0.99 and 1.01 ns per pair for 1 to 4 rows): more rows spill registers.
  /// bench/sim_loop_count.py finds the sweeps' loops by their two rows.
  static constexpr int kRows = 2;

  static void run(const PairPass& p, std::int64_t row_begin, std::int64_t row_end) {
    const double k = -2.0 * p.mbeta;
    if (k == 0.0) return run(p, row_begin, row_end, HalfBeta<0>{});
    if (k == 1.0) return run(p, row_begin, row_end, HalfBeta<1>{});
    if (k == 2.0) return run(p, row_begin, row_end, HalfBeta<2>{});
    if (k == 3.0) return run(p, row_begin, row_end, HalfBeta<3>{});
    if (k == 4.0) return run(p, row_begin, row_end, HalfBeta<4>{});
    run(p, row_begin, row_end, AnyBeta{typename Isa::Pow(p.mbeta)});
  }

  template <class Weight>
  static void run(const PairPass& pass, std::int64_t row_begin, std::int64_t row_end, const Weight& weight) {
    const PairPass p = pass;  // a local copy: the stores below cannot change it, so it stays in registers
    std::int64_t i = row_begin;
    for (; i + kRows <= row_end && i + kRows < p.n; i += kRows) {
      Rows<kRows> group;
      start(p, group, i);
      // The pairs inside the group first, row by row: (i + r, i + r + 1 .. i + kRows - 1).
      for (int r = 0; r + 1 < kRows; ++r) {
        Rows<1> one;
        start(p, one, i + r);
        block<1, true>(p, weight, i + r + 1, lane() + static_cast<double>(i + r + 1),
                       static_cast<double>(i + kRows), one);
        group.ax[r] = one.ax[0], group.ay[r] = one.ay[0], group.best[r] = one.best[0],
        group.best_j[r] = one.best_j[0];
      }
      rows(p, weight, group, i + kRows);
      for (int r = 0; r < kRows; ++r) finish(p, group, r, i + r);
    }
    for (; i < row_end; ++i) {
      Rows<1> one;
      start(p, one, i);
      rows(p, weight, one, i + 1);
      finish(p, one, 0, i);
    }
  }
};

/// `iterations` rounds of 12 independent fused multiply-adds: 12 chains cover the latency of two
/// pipes, so this runs at the core's peak multiply-add rate (the pair pass's yardstick). Returns a
/// sum of the results, which keeps them live.
template <class Isa>
double fma_chains(std::int64_t iterations) {
  using V = typename Isa::V;
  const V x = Isa::splat(0.9999999), y = Isa::splat(1e-7);
  V a0 = Isa::splat(0.0), a1 = Isa::splat(0.1), a2 = Isa::splat(0.2), a3 = Isa::splat(0.3),
    a4 = Isa::splat(0.4), a5 = Isa::splat(0.5), a6 = Isa::splat(0.6), a7 = Isa::splat(0.7),
    a8 = Isa::splat(0.8), a9 = Isa::splat(0.9), a10 = Isa::splat(1.0), a11 = Isa::splat(1.1);
  for (std::int64_t k = 0; k < iterations; ++k) {
    a0 = Isa::fma(a0, x, y), a1 = Isa::fma(a1, x, y), a2 = Isa::fma(a2, x, y), a3 = Isa::fma(a3, x, y);
    a4 = Isa::fma(a4, x, y), a5 = Isa::fma(a5, x, y), a6 = Isa::fma(a6, x, y), a7 = Isa::fma(a7, x, y);
    a8 = Isa::fma(a8, x, y), a9 = Isa::fma(a9, x, y), a10 = Isa::fma(a10, x, y), a11 = Isa::fma(a11, x, y);
  }
  double lanes[Isa::kWidth] = {};
  Isa::store(lanes, ((a0 + a1) + (a2 + a3)) + ((a4 + a5) + (a6 + a7)) + ((a8 + a9) + (a10 + a11)));
  double sum = 0.0;
  for (double l : lanes) sum += l;
  return sum;
}

}  // namespace
}  // namespace shapeform::core::batch
