#include "command.hpp"

namespace shapeform::core {

ShapeSpec shape_at(const Command& cmd, double t) {
  ShapeSpec s = cmd.shape;
  if (cmd.tracking.enabled) s.centre = centre_at(cmd.tracking.path, t);
  return s;
}

Vec2 agent_velocity(const Command& cmd, std::int32_t self_id, const Vec2& x,
                    const std::vector<Neighbour>& nbrs, double t) {
  const ShapeSpec s = shape_at(cmd, t);
  Vec2 v = paper_velocity(self_id, x, nbrs, target_point(s, x), cmd.gains);
  if (cmd.tracking.enabled && cmd.tracking.feedforward) v += centre_velocity(cmd.tracking.path, t);
  if (cmd.max_speed > 0.0) {
    const double speed = v.norm();
    if (speed > cmd.max_speed) v *= cmd.max_speed / speed;
  }
  return v;
}

StepResult agent_step(const Command& cmd, std::int32_t self_id, const Vec2& x,
                      const std::vector<Neighbour>& nbrs, double t) {
  const auto f = [&](const Vec2& y, double tau) { return agent_velocity(cmd, self_id, y, nbrs, tau); };
  const Vec2 next = integrate(cmd.integrator, f, x, t, cmd.dt);
  return {next, (next - x) / cmd.dt};
}

}  // namespace shapeform::core
