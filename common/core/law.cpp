#include "law.hpp"

#include "envelope.hpp"
#include "integrator.hpp"
#include "law_arc.hpp"
#include "law_paper.hpp"

namespace shapeform::core {

namespace {

/// The law's velocity v plus the feed-forward, within the speed limit.
Vec2 finish_velocity(const CompiledCommand& cmd, Vec2 v, double t) {
  if (cmd.tracking.enabled && cmd.tracking.feedforward) v += centre_velocity(cmd.tracking.path, t);
  if (cmd.max_speed > 0.0) {
    const double speed = v.norm();
    if (speed > cmd.max_speed) v *= cmd.max_speed / speed;
  }
  return v;
}

/// The integrator's new position `next` from x made a step: finite and inside the workspace.
StepResult finish_step(const CompiledCommand& cmd, const Vec2& x, const Vec2& next) {
  if (!next.allFinite()) return {x, Vec2::Zero(), true};
  bool clamped = false;
  const Vec2 inside = keep_inside(next, cmd.workspace, clamped);
  return {inside, (inside - x) / cmd.dt, clamped};
}

}  // namespace

Vec2 agent_velocity(const CompiledCommand& cmd, std::int32_t self_id, const Vec2& x,
                    const std::vector<Neighbour>& nbrs, double t) {
  const ShapeSpec s = shape_at(cmd, t);
  const Vec2 v = cmd.law == Law::Paper ? paper_velocity(self_id, x, nbrs, target_point(s, cmd.curve(), x), cmd.gains)
                                       : arc_velocity(s, cmd.curve(), cmd.arc, self_id, x, nbrs);
  return finish_velocity(cmd, v, t);
}

StepResult agent_step(const CompiledCommand& cmd, std::int32_t self_id, const Vec2& x,
                      const std::vector<Neighbour>& nbrs, double t) {
  if (cmd.hold) return {x, Vec2::Zero()};  // held: nobody moves (the simulator holds the same way)
  const auto f = [&](const Vec2& y, double tau) { return agent_velocity(cmd, self_id, y, nbrs, tau); };
  return finish_step(cmd, x, integrate(cmd.integrator, f, x, t, cmd.dt));
}

bool shares_steps(const CompiledCommand& cmd) {
  return !cmd.hold && cmd.law == Law::Arc && cmd.integrator == Integrator::Euler;
}

void agent_steps(const CompiledCommand& cmd, const std::vector<Neighbour>& hosted, const std::vector<Neighbour>& others,
                 double t, std::vector<StepResult>& out) {
  out.clear();
  if (!shares_steps(cmd)) {
    // Each agent on its own: its neighbours are the others and the other hosted agents.
    std::vector<Neighbour> nbrs;
    for (std::size_t k = 0; k < hosted.size(); ++k) {
      nbrs = others;
      for (std::size_t j = 0; j < hosted.size(); ++j)
        if (j != k) nbrs.push_back({hosted[j].id, hosted[j].x});
      out.push_back(agent_step(cmd, hosted[k].id, hosted[k].x, nbrs, t));
    }
    return;
  }
  thread_local std::vector<Vec2> v;
  const ShapeSpec s = shape_at(cmd, t);
  arc_velocities(s, cmd.curve(), cmd.arc, hosted, others, v);
  for (std::size_t k = 0; k < hosted.size(); ++k) {
    const Vec2 vk = finish_velocity(cmd, v[k], t);
    // Euler evaluates the velocity once, at (x, t): the one just computed.
    const auto f = [&](const Vec2&, double) { return vk; };
    out.push_back(finish_step(cmd, hosted[k].x, integrate(cmd.integrator, f, hosted[k].x, t, cmd.dt)));
  }
}

}  // namespace shapeform::core
