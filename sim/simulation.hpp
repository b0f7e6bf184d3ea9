#pragma once
/// The headless simulator: N agents in one process, each stepped with core::agent_step and driving its
/// vehicle (core::drive).
#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "core/metrics.hpp"
#include "core/swarm.hpp"

namespace shapeform::record {
class Recorder;
}

namespace shapeform::sim {

struct SimOptions {
  /// per-step metrics: header step,model_time and the core::kMetricTable names, one row per step
  /// ("" for undefined values)
  std::ostream* metrics_csv = nullptr;
  std::ostream* positions_csv = nullptr;  ///< per-step positions: step,agent,x1,x2
  /// An open recording (docs/RECORDING.md), the supervisor's layout: the command (issuer "", issuer_name
  /// shapeform_sim) at step 0, then per step the metrics, every agent's position and, when tracking,
  /// C(t). wall_s is the seconds since run_simulation began.
  record::Recorder* recorder = nullptr;
  std::uint64_t epoch = 1;  ///< the command's epoch in the recording
  core::SettleParams settle;
  core::ConvergenceParams converge;  ///< the verdict (core::ConvergenceDetector), as the supervisor's
  core::Kernel kernel = core::Kernel::Agent;  ///< see core::Kernel (Batch where core::batch_applies)
  core::BatchOptions batch;                   ///< how the batched kernel runs (instruction set, threads)
  core::VehicleParams vehicle;                ///< what every agent drives (default: the integrator)
  std::uint64_t heading_seed = 1;             ///< seeds the start headings (core::start_heading)
  /// Track the smallest pairwise distance at every step (SimResult::separation; O(N^2) per step). On
  /// whatever this says when the command's steps are filtered (core::filters).
  bool separation = false;
};

/// The options shapeform_sim runs a configuration with: the supervisor's verdict (its convergence
/// parameters and the settle bands they imply), the vehicle and the seed of the start headings.
SimOptions run_options(const core::ConvergenceParams& converge, const core::VehicleParams& vehicle,
                       std::uint64_t heading_seed);

/// The run-long safety figures: the smallest pairwise distance over every step (not a metric of one
/// snapshot, so it lives here and in the simulator's JSON summary, beside the filter's counts).
struct SeparationRecord {
  std::optional<double> min;  ///< the smallest distance between two agents at any step (start included)
  long step = 0;              ///< the first step it happened at
  double model_time = 0.0;    ///< and its model time
  long zone_entries = 0;      ///< agent-steps found inside a keep-out zone by more than 1e-9 (start included)
  double zone_depth = 0.0;    ///< the deepest any agent was inside a keep-out zone
};

/// The kernel "auto" picks: the batched one from 64 agents on, where it pays and applies (agents
/// driving the integrator model); the agent path otherwise.
core::Kernel auto_kernel(int agents, const core::VehicleParams& vehicle = {});

struct SimResult {
  core::Metrics metrics;               ///< at the final step
  std::optional<int> settle_step;      ///< see core::settle_index
  std::vector<core::Vec2> final_positions;
  /// every agent's vehicle at the final step; empty when they move exactly as the law (core::moves_as_law)
  std::vector<core::VehicleState> final_vehicles;
  long steps = 0;
  double model_time = 0.0;
  double max_step = 0.0;  ///< largest displacement of any agent in the last step (chatter)
  bool converged = false;  ///< the verdict at the final step (core::ConvergenceDetector over every step)
  core::ConvergenceDetector::Why why = core::ConvergenceDetector::Why::NoData;
  SeparationRecord separation;  ///< tracked when SimOptions::separation or the filter is on
  core::SafetyCounts safety;    ///< what the safety filter did (core::Swarm::safety_counts)
  int blocked_agents = 0;       ///< agents the filter held from the law's step at the final step
  /// per agent at the final step: the neighbour id or -2 - zone that held it, -1 when not held
  std::vector<std::int64_t> blocked_by;
  /// The first step at which the verdict said converged (nullopt: never).
  std::optional<long> converged_step;
};

/// Runs `steps` synchronous steps from `start` (the start itself is step 0 of every series).
SimResult run_simulation(const core::CompiledCommand& cmd, std::vector<core::Vec2> start, long steps,
                         const SimOptions& opt = {});

/// Reads starting positions: CSV, one "x1,x2" row per agent, optional header, '#' comments.
/// Throws std::runtime_error naming the file and line of the first problem.
std::vector<core::Vec2> read_positions_csv(const std::string& path);

}  // namespace shapeform::sim
