#pragma once
/// The batched kernel's pair pass: the O(N^2) part of the paper's law for a whole swarm, each pair once.
/// One implementation per instruction set (batch_avx512.cpp, batch_avx2.cpp, batch_generic.cpp, all from
/// batch_kernel.hpp); batch.cpp picks one at run time. This header is shared by those files, so it holds
/// declarations and plain data only: nothing the linker could take from a file built for another CPU.
#include <cstdint>

namespace shapeform::core::batch {

/// Entries every array of PairPass must hold beyond n (the widest vector reads whole vectors).
constexpr std::int64_t kPad = 8;

/// Inputs and outputs of one pair pass, as structures of arrays of n + kPad doubles each (best on
/// 64-byte boundaries: the pass's vectors then never cross a cache line).
struct PairPass {
  const double* x = nullptr;  ///< agents' first coordinates (shape units)
  const double* y = nullptr;  ///< agents' second coordinates
  std::int64_t n = 0;         ///< agents
  double s2 = 1.0;            ///< sigma^2, a normal finite double > 0
  double mbeta = -1.0;        ///< -beta, finite
  /// Outputs, accumulated into (the caller sets 0, 0, +inf, -1 first): per agent i, the sums over
  /// its partners j of w_ij (x_j - x_i) with w_ij = (sigma^2 + |x_j - x_i|^2)^-beta (not yet times
  /// k1), and the nearest partner's squared distance and index (a double; -1 for none; ties to the
  /// lowest index).
  double* sx = nullptr;
  double* sy = nullptr;
  double* nd2 = nullptr;
  double* nid = nullptr;
  /// The pass's working memory: kScratch doubles of its own (best on a 64-byte boundary).
  double* scratch = nullptr;
};

/// Doubles PairPass::scratch holds: the weights of a tile of agents j for a group of rows.
constexpr std::int64_t kScratch = 1024;

/// Adds the pairs (i, j), row_begin <= i < row_end, i < j < n, to both i's and j's outputs.
void pairs_generic(const PairPass& p, std::int64_t row_begin, std::int64_t row_end);
/// 12 x `iterations` independent vector multiply-adds at the core's peak rate; returns a checksum.
double fma_chains_generic(std::int64_t iterations);
#if defined(SHAPEFORM_BATCH_X86)
void pairs_avx2(const PairPass& p, std::int64_t row_begin, std::int64_t row_end);    ///< AVX2 + FMA
void pairs_avx512(const PairPass& p, std::int64_t row_begin, std::int64_t row_end);  ///< AVX-512 F + DQ
double fma_chains_avx2(std::int64_t iterations);
double fma_chains_avx512(std::int64_t iterations);
#endif

}  // namespace shapeform::core::batch
