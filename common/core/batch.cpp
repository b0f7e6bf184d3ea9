#include "batch.hpp"

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <limits>
#include <new>
#include <thread>

#include "batch_pairs.hpp"
#include "law.hpp"
#include "law_paper.hpp"
#include "shape.hpp"

namespace shapeform::core {

std::string_view to_string(Simd s) {
  return s == Simd::Avx512 ? "avx512" : s == Simd::Avx2 ? "avx2" : "generic";
}

std::vector<Simd> simd_available() {
  std::vector<Simd> out{Simd::Generic};
#if defined(SHAPEFORM_BATCH_X86)
  __builtin_cpu_init();  // the CPU's and the kernel's support (AVX state saved on context switches)
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) out.push_back(Simd::Avx2);
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq")) out.push_back(Simd::Avx512);
#endif
  return out;
}

Simd simd_best() {
  static const Simd best = simd_available().back();
  return best;
}

int simd_lanes(Simd s) { return s == Simd::Avx512 ? 8 : s == Simd::Avx2 ? 4 : 2; }

double fma_peak(Simd s, double seconds) {
  double (*chains)(std::int64_t) = batch::fma_chains_generic;
#if defined(SHAPEFORM_BATCH_X86)
  if (s == Simd::Avx512) chains = batch::fma_chains_avx512;
  if (s == Simd::Avx2) chains = batch::fma_chains_avx2;
#endif
  // Double the rounds until one call lasts `seconds` (the first calls also warm the core up).
  for (std::int64_t rounds = 1 << 16;; rounds *= 2) {
    const auto t0 = std::chrono::steady_clock::now();
    volatile double sink = chains(rounds);
    (void)sink;
    const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (took >= seconds || rounds >= (std::int64_t{1} << 40))
      return 12.0 * static_cast<double>(rounds) * simd_lanes(s) / took;
  }
}

namespace {

using PairFn = void (*)(const batch::PairPass&, std::int64_t, std::int64_t);

PairFn pair_fn(Simd s) {
#if defined(SHAPEFORM_BATCH_X86)
  if (s == Simd::Avx512) return batch::pairs_avx512;
  if (s == Simd::Avx2) return batch::pairs_avx2;
#endif
  (void)s;
  return batch::pairs_generic;
}

/// Storage on 64-byte boundaries: the pass's vectors (up to 8 doubles) then never cross a cache line.
template <class T>
struct CacheLineAllocator {
  using value_type = T;
  static constexpr std::align_val_t kAlign{64};
  CacheLineAllocator() = default;
  template <class U>
  CacheLineAllocator(const CacheLineAllocator<U>&) {}
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), kAlign)); }
  void deallocate(T* p, std::size_t) { ::operator delete(p, kAlign); }
  friend bool operator==(const CacheLineAllocator&, const CacheLineAllocator&) { return true; }
  friend bool operator!=(const CacheLineAllocator&, const CacheLineAllocator&) { return false; }
};
using Doubles = std::vector<double, CacheLineAllocator<double>>;

/// Four output arrays of n + kPad doubles, set as PairPass expects them, and the pass's scratch.
struct Sums {
  Doubles sx, sy, nd2, nid, scratch;
  void reset(std::size_t size) {
    scratch.resize(static_cast<std::size_t>(batch::kScratch));
    sx.assign(size, 0.0);
    sy.assign(size, 0.0);
    nd2.assign(size, std::numeric_limits<double>::infinity());
    nid.assign(size, -1.0);
  }
};

/// The first row of each of `parts` row ranges holding equal shares of the n (n - 1) / 2 pairs (row i
/// holds n - 1 - i), and n last.
std::vector<std::int64_t> row_split(std::int64_t n, int parts) {
  std::vector<std::int64_t> first{0};
  const double total = 0.5 * static_cast<double>(n) * static_cast<double>(n - 1);
  double done = 0.0;
  for (std::int64_t i = 0; i < n && static_cast<int>(first.size()) < parts; ++i) {
    done += static_cast<double>(n - 1 - i);
    if (done >= total * static_cast<double>(first.size()) / parts) first.push_back(i + 1);
  }
  first.push_back(n);
  return first;
}

}  // namespace

void paper_velocities_batch(const CompiledCommand& cmd, const std::vector<Vec2>& x, double t,
                            std::vector<Vec2>& v, const BatchOptions& opt) {
  const auto n = static_cast<std::int64_t>(x.size());
  const Gains& g = cmd.gains;
  const double s2 = g.sigma * g.sigma;
  v.resize(x.size());
  // The vectorised power wants sigma^2 normal and every weight below 2^1000; anything else (gains no
  // configuration allows, but a Command can carry) takes the per-agent law.
  if (!(s2 >= DBL_MIN && std::isfinite(s2) && std::isfinite(g.beta) && std::pow(s2, -g.beta) < 0x1p1000)) {
    std::vector<Neighbour> nbrs;
    for (std::int64_t i = 0; i < n; ++i) {
      nbrs.clear();
      for (std::int64_t j = 0; j < n; ++j)
        if (j != i) nbrs.push_back({static_cast<std::int32_t>(j), x[static_cast<std::size_t>(j)]});
      v[static_cast<std::size_t>(i)] =
          agent_velocity(cmd, static_cast<std::int32_t>(i), x[static_cast<std::size_t>(i)], nbrs, t);
    }
    return;
  }
  // Structure of arrays, reused between calls: O(N) memory, no allocation per step. (Thread-local for
  // callers on several threads; the pass's helper threads get references, not their own copies.)
  const auto size = static_cast<std::size_t>(n + batch::kPad);
  thread_local Doubles xs, ys;
  thread_local std::vector<Sums> per_part;
  Doubles &X = xs, &Y = ys;
  std::vector<Sums>& sums = per_part;
  X.assign(size, 0.0);
  Y.assign(size, 0.0);
  for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) X[i] = x[i].x(), Y[i] = x[i].y();
  const int parts =
      static_cast<int>(std::clamp<std::int64_t>(opt.threads, 1, std::max<std::int64_t>(1, n / 256)));
  sums.resize(static_cast<std::size_t>(parts));
  const PairFn pairs = pair_fn(opt.simd);
  const std::vector<std::int64_t> rows = row_split(n, parts);
  const auto pass = [&, pairs](std::size_t k) {
    Sums& s = sums[k];
    s.reset(size);
    pairs({X.data(), Y.data(), n, s2, -g.beta, s.sx.data(), s.sy.data(), s.nd2.data(), s.nid.data(),
           s.scratch.data()},
          rows[k], rows[k + 1]);
  };
  std::vector<std::thread> helpers;
  for (std::size_t k = 1; k < sums.size(); ++k) helpers.emplace_back(pass, k);
  pass(0);
  for (std::thread& h : helpers) h.join();
  // Merge the parts: sums add; the nearest is the smallest distance, ties to the lowest id.
  Sums& all = sums[0];
  for (std::size_t k = 1; k < sums.size(); ++k) {
    const Sums& s = sums[k];
    for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) {
      all.sx[i] += s.sx[i];
      all.sy[i] += s.sy[i];
      if (s.nd2[i] < all.nd2[i] || (s.nd2[i] == all.nd2[i] && s.nid[i] >= 0.0 && s.nid[i] < all.nid[i]))
        all.nd2[i] = s.nd2[i], all.nid[i] = s.nid[i];
    }
  }

  const ShapeSpec s = shape_at(cmd, t);
  const bool ff = cmd.tracking.enabled && cmd.tracking.feedforward;
  const Vec2 cv = ff ? centre_velocity(cmd.tracking.path, t) : Vec2::Zero();
  for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) {
    const Vec2& xi = x[i];
    // As paper_velocity: cohesion + attraction + repulsion, then the feed-forward and the speed limit.
    Vec2 vi = g.k1 * Vec2(all.sx[i], all.sy[i]) + attraction_term(xi, target_point(s, cmd.curve(), xi), g);
    if (all.nid[i] >= 0 && g.r != 0.0)
      vi += repulsion_from(static_cast<std::int32_t>(i), xi, x[static_cast<std::size_t>(all.nid[i])], g);
    vi += cv;
    if (cmd.max_speed > 0.0 && vi.norm() > cmd.max_speed) vi *= cmd.max_speed / vi.norm();
    v[i] = vi;
  }
}

}  // namespace shapeform::core
