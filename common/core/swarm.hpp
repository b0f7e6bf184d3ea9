#pragma once
/// An in-process swarm: N agents stepped synchronously with agent_step (the headless simulator).
#include <cstdint>
#include <vector>

#include "law.hpp"

namespace shapeform::core {

/// Seeded uniform start in [-half_width, half_width]^2 (std::mt19937_64, same seed = same start).
std::vector<Vec2> uniform_start(int n, std::uint64_t seed, double half_width = 5.0);

/// How Swarm::step computes the velocities.
enum class Kernel {
  Agent,  ///< every agent through agent_step, exactly as an agent process does (the scalar reference)
  Batch   ///< paper law + Euler only: each pair computed once, vectorised (Eigen arrays), O(N) memory;
          ///< the pair weights in single precision (relative error ~1e-7)
};

/// dx_i/dt of the paper's law for all agents at once (each pair once). v must have x's size.
/// Equal to agent_velocity for every agent to ~1e-6 relative (single-precision weights; tested).
void paper_velocities_batch(const CompiledCommand& cmd, const std::vector<Vec2>& x, double t, std::vector<Vec2>& v);

class Swarm {
 public:
  Swarm(CompiledCommand cmd, std::vector<Vec2> start);
  /// Advances every agent by one step from the same snapshot (synchronous update).
  void step();
  /// Batch is used only where it applies (paper law, Euler); elsewhere Agent.
  void set_kernel(Kernel k) { kernel_ = k; }
  Kernel kernel() const { return kernel_; }
  void set_command(const CompiledCommand& cmd) { cmd_ = cmd; }
  const CompiledCommand& command() const { return cmd_; }
  const std::vector<Vec2>& positions() const { return x_; }
  double time() const { return t_; }
  long steps() const { return steps_; }

 private:
  CompiledCommand cmd_;
  std::vector<Vec2> x_;
  std::vector<Vec2> next_;
  std::vector<Neighbour> nbrs_;
  std::vector<double> arc_;  ///< each agent's arc length this step (arc law)
  double t_ = 0.0;
  long steps_ = 0;
  Kernel kernel_ = Kernel::Agent;
  std::vector<Vec2> v_;
};

}  // namespace shapeform::core
