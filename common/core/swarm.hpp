#pragma once
/// An in-process swarm: N agents stepped synchronously with agent_step, each driving its vehicle
/// (core::drive) (the headless simulator).
#include <cstdint>
#include <vector>

#include "batch.hpp"
#include "law.hpp"
#include "vehicle.hpp"

namespace shapeform::core {

/// Seeded uniform start in [-half_width, half_width]^2 (std::mt19937_64, same seed = same start).
std::vector<Vec2> uniform_start(int n, std::uint64_t seed, double half_width = 5.0);

/// How Swarm::step computes the velocities.
enum class Kernel {
  Agent,  ///< every agent through agent_step, exactly as an agent process does (the scalar reference)
  Batch   ///< paper law + Euler only: paper_velocities_batch (each pair once, vectorised, O(N) memory)
};

/// Whether the batched kernel applies: the paper's law, Euler, and agents that drive the integrator
/// model (the other vehicle models step each agent on its own).
bool batch_applies(const CompiledCommand& cmd, const VehicleParams& vehicle);

class Swarm {
 public:
  Swarm(CompiledCommand cmd, std::vector<Vec2> start);
  /// Advances every agent by one step from the same snapshot (synchronous update).
  void step();
  /// Batch is used only where it applies (batch_applies); elsewhere Agent.
  void set_kernel(Kernel k) { kernel_ = k; }
  Kernel kernel() const { return kernel_; }
  /// How the batched kernel runs (instruction set, threads).
  void set_batch(const BatchOptions& b) { batch_ = b; }
  void set_command(const CompiledCommand& cmd) { cmd_ = cmd; }
  const CompiledCommand& command() const { return cmd_; }
  /// The vehicle every agent drives (default: the integrator, positions exactly as the law steps them),
  /// agent i starting with headings[i] (empty: p.initial_heading). Call before the first step; throws
  /// std::invalid_argument when headings has another size than the swarm.
  void set_vehicle(const VehicleParams& p, const std::vector<double>& headings = {});
  const VehicleParams& vehicle() const { return vehicle_; }
  /// Every agent's vehicle state; empty while they move exactly as the law steps them (moves_as_law).
  const std::vector<VehicleState>& vehicles() const { return vehicles_; }
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
  VehicleParams vehicle_;
  std::vector<VehicleState> vehicles_;
  /// Where agent i's vehicle takes it on the law's step r (r.x itself when it moves as the law).
  Vec2 move(int i, const StepResult& r);
  void step_batch();
};

}  // namespace shapeform::core
