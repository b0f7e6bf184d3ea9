#pragma once
/// An in-process swarm: N agents stepped synchronously with agent_step, each driving its vehicle
/// (core::drive) (the headless simulator).
#include <cstdint>
#include <vector>

#include "batch.hpp"
#include "law.hpp"
#include "safety.hpp"
#include "vehicle.hpp"

namespace shapeform::core {

/// Seeded uniform start in [-half_width, half_width]^2 (std::mt19937_64, same seed = same start).
std::vector<Vec2> uniform_start(int n, std::uint64_t seed, double half_width = 5.0);

/// How Swarm::step computes the velocities.
enum class Kernel {
  Agent,  ///< every agent through agent_step, exactly as an agent process does (the scalar reference)
  Batch   ///< paper law + Euler only: paper_velocities_batch (each pair once, vectorised, O(N) memory)
};

/// Whether the batched kernel applies: the paper's law, Euler, agents that drive the integrator model
/// (the other vehicle models step each agent on its own) and no safety filter (core::filters: each
/// agent's step is filtered on its own).
bool batch_applies(const CompiledCommand& cmd, const VehicleParams& vehicle);

/// What the safety filter did over a run (core::safety_filter on every agent's step).
struct SafetyCounts {
  long interventions = 0;  ///< agent-steps whose position the filter moved
  long sidesteps = 0;      ///< deadlock sidesteps begun
  long broken = 0;         ///< (agent, neighbour) pairs found closer than min_separation, per step
  long held = 0;           ///< agent-steps held (cut below stuck_fraction while the law asks to move)
  long outside = 0;        ///< agent-steps whose vehicle could not be landed in its cell (drive_safely)
};

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
  void set_command(const CompiledCommand& cmd);
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
  /// The safety filter's counts since the start (all 0 while core::filters(command) is false).
  const SafetyCounts& safety_counts() const { return counts_; }
  /// Agents the filter held or sidestepped on the last step (they are not where the law sends them).
  int blocked_agents() const { return blocked_; }
  /// The neighbour (id) or zone that held each agent on the last step: -1 when not held; a zone k is
  /// given as -2 - k.
  const std::vector<std::int64_t>& blocked_by() const { return blocked_by_; }
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
  /// Agent i's step r through the safety filter, then its vehicle.
  Vec2 move_safely(int i, const StepResult& r);

  std::vector<ConvexZone> zones_;       ///< the command's keep-out zones in convex pieces
  SafetyParams safety_;                 ///< from the command and the vehicle
  std::vector<SafetyState> safety_state_;
  std::vector<SafetyNeighbour> snbrs_;
  std::vector<Vec2> brakes_;  ///< double integrators: each one's braking displacement at the step's start
  SafetyCounts counts_;
  int blocked_ = 0;
  std::vector<std::int64_t> blocked_by_;
};

}  // namespace shapeform::core
