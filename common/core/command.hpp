#pragma once
/// What an agent is told to do, and the single step every agent (process or simulated) takes.
#include <vector>

#include "integrator.hpp"
#include "law.hpp"
#include "shape.hpp"

namespace shapeform::core {

/// Tracking: the shape's centre follows a path; the shape is drawn around C(t).
struct Tracking {
  bool enabled = false;
  CentrePath path;
  bool feedforward = false;  ///< add dC/dt to every agent's velocity
};

/// The full command an agent follows (what the supervisor publishes).
struct Command {
  ShapeSpec shape;
  Tracking tracking;
  Gains gains;
  Integrator integrator = Integrator::Euler;
  double dt = 1.0;         ///< model time per step (one paper iteration = 1)
  double max_speed = 0.0;  ///< speed limit in units per model time; 0 = none
};

/// The shape in force at model time t (tracked shapes are centred on C(t)).
ShapeSpec shape_at(const Command& cmd, double t);

/// dx/dt of agent self_id at x and model time t, given its neighbours' positions.
Vec2 agent_velocity(const Command& cmd, std::int32_t self_id, const Vec2& x,
                    const std::vector<Neighbour>& nbrs, double t);

struct StepResult {
  Vec2 x;  ///< new position
  Vec2 v;  ///< velocity used over the step ((x_new - x) / dt)
};

/// One integration step of agent self_id from model time t to t + cmd.dt, neighbours held fixed.
/// This is the one function the simulator and the agent process both call.
StepResult agent_step(const Command& cmd, std::int32_t self_id, const Vec2& x,
                      const std::vector<Neighbour>& nbrs, double t);

}  // namespace shapeform::core
