// The dispatcher: the law the command names, then feed-forward and the speed limit, integrated.
#include <catch2/catch.hpp>
#include <cmath>

#include "core/law.hpp"
#include "core/law_arc.hpp"
#include "core/law_paper.hpp"

using namespace shapeform::core;

TEST_CASE("agent velocity is the law the command names", "[law]") {
  Command plain;
  plain.shape.kind = ShapeKind::Ellipse;
  plain.shape.centre = Vec2(1, -2);
  plain.shape.rotation = 0.3;
  CompiledCommand cmd = compile(plain);
  const Vec2 x(3.5, 1.25);
  const std::vector<Neighbour> nbrs = {{1, Vec2(2, 2)}, {2, Vec2(-1, 0.5)}, {3, Vec2(0, -4)}};
  const Vec2 xt = target_point(cmd.shape, cmd.curve(), x);
  CHECK(agent_velocity(cmd, 0, x, nbrs, 5) == paper_velocity(0, x, nbrs, xt, cmd.gains));
  cmd.law = Law::Arc;
  CHECK(agent_velocity(cmd, 0, x, nbrs, 5) == arc_velocity(cmd.shape, cmd.curve(), cmd.arc, 0, x, nbrs));
  // Each agent moves by its velocity over one Euler step.
  const StepResult r = agent_step(cmd, 0, x, nbrs, 5);
  CHECK(r.x == x + cmd.dt * arc_velocity(cmd.shape, cmd.curve(), cmd.arc, 0, x, nbrs));
}

TEST_CASE("agent velocity: feed-forward adds dC/dt, max_speed clamps", "[law][tracking]") {
  Command ring;
  ring.shape.kind = ShapeKind::Circle;
  ring.shape.r0 = 2;
  CompiledCommand cmd = compile(ring);
  cmd.tracking.enabled = true;
  cmd.tracking.path.kind = CentrePath::Kind::Line;
  cmd.tracking.path.point = Vec2(-10, -10);
  cmd.tracking.path.velocity = Vec2(0.1, 0.1);
  const Vec2 x(1, 1);
  const Vec2 plain = agent_velocity(cmd, 0, x, {}, 20);
  // At t = 20 the centre is (-8, -8): the target is on the ring of radius 2 around it.
  const Vec2 c(-8, -8);
  CHECK((plain - attraction_term(x, c + 2 * (x - c).normalized(), cmd.gains)).norm() < 1e-14);
  cmd.tracking.feedforward = true;
  CHECK((agent_velocity(cmd, 0, x, {}, 20) - (plain + Vec2(0.1, 0.1))).norm() < 1e-15);
  cmd.max_speed = 0.01;
  CHECK(agent_velocity(cmd, 0, x, {}, 20).norm() == Approx(0.01));
}

TEST_CASE("a held command moves nobody, with either law and integrator", "[law][hold]") {
  Command c;
  c.shape.kind = ShapeKind::Circle;
  c.tracking.enabled = true;
  c.tracking.feedforward = true;
  c.tracking.path.kind = CentrePath::Kind::Line;
  c.tracking.path.velocity = Vec2(0.5, 0);
  c.hold = true;
  const std::vector<Neighbour> nbrs = {{1, Vec2(2, 2)}, {2, Vec2(-1, 0.5)}};
  for (const Law law : {Law::Paper, Law::Arc}) {
    for (const Integrator integ : {Integrator::Euler, Integrator::RK4}) {
      c.law = law;
      c.integrator = integ;
      const StepResult r = agent_step(compile(c), 0, Vec2(3.5, 1.25), nbrs, 7);
      CHECK(r.x == Vec2(3.5, 1.25));
      CHECK(r.v == Vec2::Zero());
    }
  }
  c.hold = false;  // the same command released moves the agent
  CHECK(agent_step(compile(c), 0, Vec2(3.5, 1.25), nbrs, 7).x != Vec2(3.5, 1.25));
}
