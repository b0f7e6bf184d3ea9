#pragma once
/// What the supervisor knows of the swarm, without DDS or clocks: the latest state of every agent,
/// who is alive, the command in force and the model clock of its epoch, and the convergence metrics
/// (computed with the same core functions as the simulator).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/metrics.hpp"
#include "protocol/samples.hpp"
#include "util/id_map.hpp"

namespace shapeform::supervisor {

struct AgentView {
  core::Vec2 x = core::Vec2::Zero();
  core::Vec2 prev_x = core::Vec2::Zero();  ///< position one step earlier (AgentState.prev_x/prev_y)
  core::Vec2 v = core::Vec2::Zero();       ///< velocity over its last step (AgentState.vx/vy)
  dds::CommandId command;       ///< the command the agent follows (epoch 0: none yet)
  double model_time = 0.0;      ///< the agent's model time
  std::int64_t last_seen_ns = 0;
  bool departed = false;        ///< disposed its instance (clean exit)
  // From the agent's status topic (absent until the first status).
  std::optional<int> neighbours_heard;
  std::uint64_t samples_rejected = 0;
  dds::StatusSample status;  ///< the latest status (its safety figures are of the command status.epoch)
  dds::SourceId source;                    ///< the participant that publishes it (unknown: all zeros)
  std::vector<dds::SourceId> duplicates;   ///< other participants seen publishing its id (reported)
};

class SwarmMonitor {
 public:
  /// lockstep: the agents step together (agent.sync = lockstep), so a sample at model time t takes
  /// every agent at step t, the previous position of those already one step further.
  /// idle_timeout_ns: how long an agent that follows no command yet may stay unheard (it publishes at
  /// agent.idle_rate_hz until its first command); 0 = agent_timeout_ns.
  SwarmMonitor(std::int64_t agent_timeout_ns, core::ConvergenceDetector::Params converge, bool lockstep = false,
               std::int64_t idle_timeout_ns = 0);

  /// Whose a sample of agent `id` from participant `source` is. Owner: the id is unknown, not alive,
  /// or published by that same participant (or either participant is unknown), so the sample is the
  /// agent's. Otherwise another participant publishes an id in use (two processes started with one
  /// --id): NewDuplicate the first time that participant is seen on the id, Duplicate after; such
  /// samples are not the agent's (the incumbent keeps the id until it leaves or falls silent).
  enum class Claim { Owner, NewDuplicate, Duplicate };
  Claim claim(std::int32_t id, const dds::SourceId& source, std::int64_t now_ns);

  /// A state of agent id (source: the participant that published it, see claim(); v: its velocity).
  void on_state(std::int32_t id, const core::Vec2& x, const core::Vec2& prev_x, dds::CommandId command,
                double model_time, std::int64_t now_ns, const dds::SourceId& source = {},
                const core::Vec2& v = core::Vec2::Zero());
  void on_status(const dds::StatusSample& s);
  void on_departed(std::int32_t id);

  /// A new command is in force from now (its epoch's model clock starts at 0): the metrics measure
  /// against it, and "following" means following it.
  void set_command(const core::CompiledCommand& cmd, dds::CommandId id, std::int64_t now_ns);
  const std::optional<core::CompiledCommand>& command() const { return command_; }
  std::uint64_t epoch() const { return id_.epoch; }
  const dds::CommandId& command_id() const { return id_; }
  /// The highest epoch any agent was seen following (a restarted supervisor continues after it).
  std::uint64_t max_epoch_seen() const { return max_epoch_seen_; }
  /// The lowest non-zero epoch an alive agent follows (0: none): what a supervisor that knows no command
  /// yet judges epoch jumps from (dds::CommandArbiter).
  std::uint64_t min_epoch_followed(std::int64_t now_ns) const;

  bool alive(const AgentView& a, std::int64_t now_ns) const;
  int alive_count(std::int64_t now_ns) const;
  /// Alive agents following the current epoch.
  int following_count(std::int64_t now_ns) const;
  /// Every agent heard, ascending ids.
  const util::IdMap<AgentView>& agents() const { return agents_; }

  /// Whether every alive agent reported (in its latest status) hearing at least `count` neighbours.
  bool all_hear(int count, std::int64_t now_ns) const;
  /// The smallest model time among alive agents following the current epoch (how far every one of them
  /// has got), or nullopt when none follows it.
  std::optional<double> min_following_model_time(std::int64_t now_ns) const;
  /// Ids and positions of alive agents, ascending id: the latest, or in lockstep those at model time
  /// `at` when given.
  std::vector<std::pair<std::int32_t, core::Vec2>> alive_positions(std::int64_t now_ns,
                                                                   std::optional<double> at = std::nullopt) const;

  /// The run's safety figures of the current command (core::Metrics' run fields) from the agents'
  /// latest statuses of it and the metrics samples since the command; the fence and filter figures
  /// stay null until an agent reports one.
  void run_figures(core::Metrics& m, std::int64_t now_ns) const;

  /// The metrics of the alive agents at model time t. No command: all null.
  struct Sample {
    double model_time = 0.0;
    core::Metrics metrics;
    bool converged = false;
    core::ConvergenceDetector::Why why = core::ConvergenceDetector::Why::NoData;  ///< the verdict's reason
    std::optional<double> spread;  ///< core::spread of the alive agents (the verdict's growth measure)
    int alive = 0;
    int following = 0;
  };
  /// Computes the sample and feeds it to the convergence detector and the settling history.
  /// Converged needs every alive agent on the current epoch.
  Sample update(double model_time, std::int64_t now_ns);
  /// The same sample without feeding anything: `converged` is the detector's verdict so far (the
  /// final summary reports what the published metrics said, not one more sample).
  Sample measure(double model_time, std::int64_t now_ns) const;
  const std::optional<Sample>& last() const { return last_; }
  bool converged() const { return detector_.converged(); }
  /// Model time at which the current epoch settled (core::settle_index over this epoch's samples).
  std::optional<double> settle_time(const core::SettleParams& p) const;

 private:
  std::int64_t agent_timeout_ns_;
  std::int64_t idle_timeout_ns_;  ///< for agents that follow no command yet
  core::ConvergenceDetector detector_;
  bool lockstep_;
  util::IdMap<AgentView> agents_;  ///< found by id many thousand times a second: no tree
  std::optional<core::CompiledCommand> command_;
  dds::CommandId id_;
  std::uint64_t max_epoch_seen_ = 0;
  std::optional<Sample> last_;
  std::vector<double> hist_t_, hist_err_;
  std::vector<std::optional<double>> hist_gap_;
  /// The smallest metrics sample's min_separation since the command, and its model time.
  std::optional<std::pair<double, double>> sampled_min_;
};

}  // namespace shapeform::supervisor
