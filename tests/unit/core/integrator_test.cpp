#include <catch2/catch.hpp>
#include <cmath>

#include "core/law.hpp"
#include "core/integrator.hpp"

using namespace shapeform::core;

namespace {
/// Error at T of integrating dx/dt = f from x0 with step dt.
template <class F>
double error_at(Integrator m, F f, Vec2 x0, double T, double dt, const Vec2& exact) {
  Vec2 x = x0;
  const int n = static_cast<int>(std::lround(T / dt));
  for (int k = 0; k < n; ++k) x = integrate(m, f, x, k * dt, dt);
  return (x - exact).norm();
}
}  // namespace

TEST_CASE("Euler is first order and RK4 fourth order on a rotation", "[integrator]") {
  const auto f = [](const Vec2& x, double) { return Vec2(-x.y(), x.x()); };
  const Vec2 x0(1, 0);
  const double T = 1.0;
  const Vec2 exact(std::cos(T), std::sin(T));
  const double e1 = error_at(Integrator::Euler, f, x0, T, 0.01, exact);
  const double e2 = error_at(Integrator::Euler, f, x0, T, 0.005, exact);
  CHECK(e1 / e2 == Approx(2.0).epsilon(0.05));
  const double r1 = error_at(Integrator::RK4, f, x0, T, 0.1, exact);
  const double r2 = error_at(Integrator::RK4, f, x0, T, 0.05, exact);
  CHECK(r1 / r2 == Approx(16.0).epsilon(0.1));
}

TEST_CASE("RK4 sees time: a time-dependent field", "[integrator]") {
  // dx/dt = (cos t, 0): x(T) = sin T.
  const auto f = [](const Vec2&, double t) { return Vec2(std::cos(t), 0.0); };
  const double r1 = error_at(Integrator::RK4, f, Vec2::Zero(), 2.0, 0.2, Vec2(std::sin(2.0), 0));
  const double r2 = error_at(Integrator::RK4, f, Vec2::Zero(), 2.0, 0.1, Vec2(std::sin(2.0), 0));
  CHECK(r1 / r2 == Approx(16.0).epsilon(0.15));
}

TEST_CASE("agent_step orders on the law itself (smooth case: one agent, a line)", "[integrator]") {
  Command line;
  line.shape.kind = ShapeKind::Line;
  CompiledCommand cmd = compile(line);
  const Vec2 x0(-3, -2);
  const double T = 4.0;
  const auto run = [&](Integrator m, double dt) {
    cmd.integrator = m;
    cmd.dt = dt;
    Vec2 x = x0;
    const int n = static_cast<int>(std::lround(T / dt));
    for (int k = 0; k < n; ++k) x = agent_step(cmd, 0, x, {}, k * dt).x;
    return x;
  };
  const Vec2 ref = run(Integrator::RK4, 0.001);
  const double e1 = (run(Integrator::Euler, 0.02) - ref).norm();
  const double e2 = (run(Integrator::Euler, 0.01) - ref).norm();
  CHECK(e1 / e2 == Approx(2.0).epsilon(0.1));
  const double r1 = (run(Integrator::RK4, 0.4) - ref).norm();
  const double r2 = (run(Integrator::RK4, 0.2) - ref).norm();
  CHECK(r1 / r2 == Approx(16.0).epsilon(0.25));
  // One paper iteration is one Euler step of dt = 1: x + f(x).
  cmd.integrator = Integrator::Euler;
  cmd.dt = 1.0;
  const StepResult s = agent_step(cmd, 0, x0, {}, 0);
  CHECK((s.x - (x0 + agent_velocity(cmd, 0, x0, {}, 0))).norm() < 1e-15);
  CHECK((s.v - agent_velocity(cmd, 0, x0, {}, 0)).norm() < 1e-15);
}

TEST_CASE("integrator names round-trip", "[integrator]") {
  Integrator i{};
  CHECK(parse_integrator("rk4", i));
  CHECK(i == Integrator::RK4);
  CHECK(parse_integrator(to_string(Integrator::Euler), i));
  CHECK(i == Integrator::Euler);
  CHECK_FALSE(parse_integrator("midpoint", i));
}
