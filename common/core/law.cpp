#include "law.hpp"

#include "envelope.hpp"
#include "integrator.hpp"
#include "law_arc.hpp"
#include "law_paper.hpp"

namespace shapeform::core {

Vec2 agent_velocity(const CompiledCommand& cmd, std::int32_t self_id, const Vec2& x,
                    const std::vector<Neighbour>& nbrs, double t) {
  const ShapeSpec s = shape_at(cmd, t);
  Vec2 v = cmd.law == Law::Paper ? paper_velocity(self_id, x, nbrs, target_point(s, cmd.curve(), x), cmd.gains)
                                 : arc_velocity(s, cmd.curve(), cmd.arc, self_id, x, nbrs);
  if (cmd.tracking.enabled && cmd.tracking.feedforward) v += centre_velocity(cmd.tracking.path, t);
  if (cmd.max_speed > 0.0) {
    const double speed = v.norm();
    if (speed > cmd.max_speed) v *= cmd.max_speed / speed;
  }
  return v;
}

StepResult agent_step(const CompiledCommand& cmd, std::int32_t self_id, const Vec2& x,
                      const std::vector<Neighbour>& nbrs, double t) {
  if (cmd.hold) return {x, Vec2::Zero()};  // held: nobody moves (the simulator holds the same way)
  const auto f = [&](const Vec2& y, double tau) { return agent_velocity(cmd, self_id, y, nbrs, tau); };
  const Vec2 next = integrate(cmd.integrator, f, x, t, cmd.dt);
  if (!next.allFinite()) return {x, Vec2::Zero(), true};
  bool clamped = false;
  const Vec2 inside = keep_inside(next, cmd.workspace, clamped);
  return {inside, (inside - x) / cmd.dt, clamped};
}

}  // namespace shapeform::core
