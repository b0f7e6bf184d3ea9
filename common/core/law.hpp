#pragma once
/// The control law in force: the one place that picks the paper's law (law_paper) or the arc law
/// (law_arc) for a command, adds the feed-forward and applies the speed limit; agent_step integrates
/// it. The simulator and the agent process both call agent_step, so they compute the same numbers.
#include <cstdint>
#include <vector>

#include "compiled_command.hpp"
#include "types.hpp"

namespace shapeform::core {

/// dx/dt of agent self_id at x and model time t, given its neighbours.
Vec2 agent_velocity(const CompiledCommand& cmd, std::int32_t self_id, const Vec2& x,
                    const std::vector<Neighbour>& nbrs, double t);

struct StepResult {
  Vec2 x;  ///< new position
  Vec2 v;  ///< velocity used over the step ((x_new - x) / dt)
  /// The law's step would have left the workspace (moved back inside it) or was not finite (not
  /// taken: the agent stays where it was).
  bool clamped = false;
};

/// One integration step of agent self_id from model time t to t + cmd.dt, neighbours held fixed.
/// A held command (cmd.hold) leaves x where it is, with velocity 0. The new position is always finite
/// and inside the workspace (core::keep_inside): an agent never takes a position its peers would
/// refuse, and a swarm carried to the edge comes back when commanded back.
StepResult agent_step(const CompiledCommand& cmd, std::int32_t self_id, const Vec2& x,
                      const std::vector<Neighbour>& nbrs, double t);

/// Whether agent_steps shares its work between the agents (the arc law integrated by Euler, not
/// held): one sorted arc list and one offset for all (core::arc_velocities) instead of one per agent.
/// Otherwise (the paper's law, RK4 whose stages move each agent's own arc length) it steps each
/// agent on its own.
bool shares_steps(const CompiledCommand& cmd);

/// One step of several agents that see one swarm (the agents one process hosts), from model time t:
/// out[k] is agent_step(cmd, hosted[k].id, hosted[k].x, nbrs_k, t) with nbrs_k = `others` plus the
/// other hosted agents (their arc lengths unknown: projected, as each projects itself), bit for bit
/// (tests/unit/core/law_arc_batch_test.cpp). Ids are distinct across both lists.
void agent_steps(const CompiledCommand& cmd, const std::vector<Neighbour>& hosted, const std::vector<Neighbour>& others,
                 double t, std::vector<StepResult>& out);

}  // namespace shapeform::core
