#pragma once
/// The batched kernel: the paper's law for a whole swarm at once (the simulator's fast path). Each pair
/// is computed once, in vectors as wide as the CPU it runs on offers (chosen at run time, so one build
/// runs everywhere), in O(N) memory, and gives the per-agent law's results (core::agent_velocity) to
/// rounding: the same nearest neighbours, the pair weights to 1e-14 relative (a few 1e-16 without AVX-512).
#include <string_view>
#include <vector>

#include "compiled_command.hpp"
#include "types.hpp"

namespace shapeform::core {

/// Instruction sets of the batched kernel's pair pass.
enum class Simd {
  Generic,  ///< two-lane vectors, any CPU (SSE2 on x86-64)
  Avx2,     ///< four lanes, AVX2 and FMA
  Avx512    ///< eight lanes, AVX-512 F and DQ
};
std::string_view to_string(Simd s);
/// The instruction sets this CPU and this build run, Generic first.
std::vector<Simd> simd_available();
/// The widest of simd_available().
Simd simd_best();

/// Lanes per vector of s (2, 4 or 8 doubles).
int simd_lanes(Simd s);

/// Double-precision multiply-adds per second one thread sustains with s on this CPU (lanes x vector
/// multiply-adds per second, measured over about `seconds` on independent chains): the peak the
/// pair pass is compared with. Without FMA (Generic) a multiply and an add count as one.
double fma_peak(Simd s, double seconds = 0.2);

/// How paper_velocities_batch runs.
struct BatchOptions {
  Simd simd = simd_best();  ///< must be one of simd_available()
  /// Threads of the pair pass, each taking rows that hold an equal share of the pairs (1: the calling
  /// thread only). The sums' rounding depends on it, nothing else.
  int threads = 1;
};

/// dx_i/dt of the paper's law for all agents at once: v[i] = agent_velocity(cmd, i, x[i], others, t)
/// to rounding (tested). Gains outside the vectorised power's range (sigma^-2beta above 2^1000)
/// take the per-agent law itself.
void paper_velocities_batch(const CompiledCommand& cmd, const std::vector<Vec2>& x, double t,
                            std::vector<Vec2>& v, const BatchOptions& opt = {});

}  // namespace shapeform::core
