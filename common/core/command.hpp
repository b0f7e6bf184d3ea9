#pragma once
/// What an agent is told to do, and the single step every agent (process or simulated) takes.
#include <vector>

#include "integrator.hpp"
#include "law.hpp"
#include "shape.hpp"

namespace shapeform::core {

/// Which control law the agents run.
enum class Law {
  Paper,  ///< Goswami et al. eq. 2 (the default, untouched)
  Arc     ///< arc-length slots: exact, evenly spaced, chatter-free (docs/LAW.md)
};
std::string_view to_string(Law l);
bool parse_law(std::string_view name, Law& out);

/// Parameters of the arc law.
struct ArcParams {
  double k_normal = 0.5;   ///< rate toward the curve point ahead (1/model time; k_normal dt <= 1)
  double k_tangent = 1.0;  ///< fraction of the slot error taken per step along the curve
  double spacing = 1.0;    ///< gap between agents on an infinite line (shape units)
};

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
  Law law = Law::Paper;
  ArcParams arc;
};

/// The arc law's velocity for agent self_id at x on shape s (placed at its current centre).
/// Neighbours' arc lengths are used when given (finite), else computed from their positions.
Vec2 arc_velocity(const ShapeSpec& s, const Curve& curve, const ArcParams& p, std::int32_t self_id,
                  const Vec2& x, const std::vector<Neighbour>& nbrs);

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
