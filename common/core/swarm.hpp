#pragma once
/// An in-process swarm: N agents stepped synchronously with agent_step (the headless simulator).
#include <cstdint>
#include <vector>

#include "batch.hpp"
#include "law.hpp"

namespace shapeform::core {

/// Seeded uniform start in [-half_width, half_width]^2 (std::mt19937_64, same seed = same start).
std::vector<Vec2> uniform_start(int n, std::uint64_t seed, double half_width = 5.0);

/// How Swarm::step computes the velocities.
enum class Kernel {
  Agent,  ///< every agent through agent_step, exactly as an agent process does (the scalar reference)
  Batch   ///< paper law + Euler only: paper_velocities_batch (each pair once, vectorised, O(N) memory)
};

class Swarm {
 public:
  Swarm(CompiledCommand cmd, std::vector<Vec2> start);
  /// Advances every agent by one step from the same snapshot (synchronous update).
  void step();
  /// Batch is used only where it applies (paper law, Euler); elsewhere Agent.
  void set_kernel(Kernel k) { kernel_ = k; }
  Kernel kernel() const { return kernel_; }
  /// How the batched kernel runs (instruction set, threads).
  void set_batch(const BatchOptions& b) { batch_ = b; }
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
  BatchOptions batch_;
  std::vector<Vec2> v_;
};

}  // namespace shapeform::core
