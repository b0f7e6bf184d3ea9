// Vehicle models (core/vehicle.hpp): limits, kinematics, and the integrator model's bit-identity.
#include "core/vehicle.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "core/law.hpp"
#include "core/swarm.hpp"

using namespace shapeform::core;

namespace {

constexpr double kPi = 3.14159265358979323846;
/// Rounding allowance of a limit (the saturations scale by limit / norm).
constexpr double kUlps = 1e-12;

/// A law step from s.x to s.x + step over dt.
StepResult law_step(const VehicleState& s, const Vec2& step, double dt) { return {s.x + step, step / dt}; }

/// Random limits (each sometimes off), offset and time scale.
VehicleParams random_params(VehicleModel model, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  VehicleParams p;
  p.model = model;
  p.steering = u(rng) < 0.5 ? Steering::Exact : Steering::Linearised;
  p.max_speed = u(rng) < 0.2 ? 0.0 : 0.05 + 2.0 * u(rng);
  p.max_yaw_rate = u(rng) < 0.2 ? 0.0 : 0.05 + 3.0 * u(rng);
  p.max_accel = u(rng) < 0.2 ? 0.0 : 0.01 + 2.0 * u(rng);
  p.offset = 0.01 + u(rng);
  p.seconds_per_model_time = u(rng) < 0.5 ? 1.0 : 0.01 + 2.0 * u(rng);
  return p;
}

Vec2 random_vec(std::mt19937_64& rng, double scale) {
  std::normal_distribution<double> g(0.0, scale);
  return {g(rng), g(rng)};
}

/// The axle's displacement over a step, in the frame of the heading half-way through the turn: a
/// unicycle's axle runs an arc tangent to its heading, whose chord lies along that mean heading.
Vec2 chord_in_mean_frame(const VehicleParams& p, const VehicleState& before, const VehicleState& after,
                         double turn) {
  const Vec2 d = axle(p, after) - axle(p, before);
  const double m = before.heading + 0.5 * turn;
  return {std::cos(m) * d.x() + std::sin(m) * d.y(), -std::sin(m) * d.x() + std::cos(m) * d.y()};
}

}  // namespace

TEST_CASE("vehicle: no command ever exceeds a limit (random steps, states and limits)", "[vehicle]") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  for (VehicleModel model :
       {VehicleModel::Integrator, VehicleModel::DoubleIntegrator, VehicleModel::Unicycle}) {
    for (int trial = 0; trial < 20000; ++trial) {
      const VehicleParams p = random_params(model, rng);
      VehicleState s = vehicle_start(random_vec(rng, 10.0), angle(rng));
      const Vec2 v0 = random_vec(rng, 1.0);
      s.velocity = p.max_speed > 0 && v0.norm() > p.max_speed ? Vec2(v0 * (p.max_speed / v0.norm())) : v0;
      const VehicleState before = s;
      const double dt = trial % 3 == 0 ? 1.0 : 0.25;
      const double h = dt * p.seconds_per_model_time;
      const StepResult r = drive(p, s, law_step(s, random_vec(rng, trial % 2 ? 0.1 : 5.0), dt), dt, 1000.0);
      INFO("model " << to_string(model) << " trial " << trial);
      REQUIRE(s.x.allFinite());
      CHECK(r.x == s.x);
      if (model == VehicleModel::Unicycle) {
        if (p.max_speed > 0) CHECK(std::abs(s.speed) <= p.max_speed);
        if (p.max_yaw_rate > 0) CHECK(std::abs(s.yaw_rate) <= p.max_yaw_rate);
      } else {
        if (p.max_speed > 0) CHECK(s.velocity.norm() <= p.max_speed * (1 + kUlps));
        // The position's own rounding (|x| up to about 40) comes on top.
        if (p.max_speed > 0) CHECK((s.x - before.x).norm() <= p.max_speed * h * (1 + kUlps) + 1e-13);
      }
      if (model == VehicleModel::DoubleIntegrator && p.max_accel > 0)
        CHECK((s.velocity - before.velocity).norm() <= p.max_accel * h * (1 + kUlps));
    }
  }
}

TEST_CASE("vehicle: a unicycle cannot move sideways", "[vehicle][unicycle]") {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  for (int trial = 0; trial < 5000; ++trial) {
    const VehicleParams p = random_params(VehicleModel::Unicycle, rng);
    VehicleState s = vehicle_start(random_vec(rng, 10.0), angle(rng));
    const VehicleState before = s;
    drive(p, s, law_step(s, random_vec(rng, 2.0), 1.0), 1.0, 1000.0);
    const double turn = s.yaw_rate * p.seconds_per_model_time;
    const Vec2 c = chord_in_mean_frame(p, before, s, turn);
    INFO("trial " << trial);
    CHECK(std::abs(c.y()) <= 1e-12 * (1.0 + c.norm()));
    // Its length is the arc's chord: |v| h sinc(turn / 2).
    const double sinc = std::abs(turn) < 1e-8 ? 1.0 : std::sin(0.5 * turn) / (0.5 * turn);
    CHECK(c.x() == Approx(s.speed * p.seconds_per_model_time * sinc).margin(1e-12));
    CHECK((s.x - axle(p, s)).norm() == Approx(p.offset));
  }
  // The exact arc equals many small straight moves along the heading (the kinematics' integral).
  VehicleParams p;
  p.model = VehicleModel::Unicycle;
  VehicleState arc = vehicle_start(Vec2(1, 2), 0.3), fine = arc;
  const UnicycleCommand c{0.8, 1.7};
  unicycle_move(p, arc, c, 1.0);
  Vec2 a = axle(p, fine);
  double th = fine.heading;
  const int k = 100000;
  for (int i = 0; i < k; ++i) {
    a += (c.v / k) * heading_vector(th + 0.5 * c.w / k);  // midpoint rule per sub-step
    th += c.w / k;
  }
  CHECK((axle(p, arc) - a).norm() < 1e-9);
  CHECK(std::remainder(arc.heading - th, 2 * kPi) == Approx(0).margin(1e-9));  // the sum's rounding
}

TEST_CASE("vehicle: exact steering puts the unicycle's point at the law's step", "[vehicle][unicycle]") {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  VehicleParams p;
  p.model = VehicleModel::Unicycle;
  for (int trial = 0; trial < 5000; ++trial) {
    VehicleState s = vehicle_start(random_vec(rng, 10.0), angle(rng));
    const Vec2 want = s.x + random_vec(rng, trial % 2 ? 0.05 : 3.0);  // any direction, backwards too
    drive(p, s, law_step(s, want - s.x, 1.0), 1.0, 1000.0);
    CHECK((s.x - want).norm() < 1e-12);
  }
  // With limits the point still moves along the law's step, only shorter.
  p.max_speed = 0.3;
  p.max_yaw_rate = 0.5;
  for (int trial = 0; trial < 5000; ++trial) {
    VehicleState s = vehicle_start(random_vec(rng, 10.0), angle(rng));
    const Vec2 from = s.x;
    const Vec2 step = random_vec(rng, 3.0);
    drive(p, s, law_step(s, step, 1.0), 1.0, 1000.0);
    const Vec2 moved = s.x - from;
    CHECK(std::abs(step.x() * moved.y() - step.y() * moved.x()) <= 1e-10 * step.norm());
    CHECK(moved.dot(step) >= 0.0);
    CHECK(moved.norm() <= step.norm() * (1 + kUlps));
  }
}

TEST_CASE("vehicle: the double integrator's acceleration is bounded and its fixed point kept", "[vehicle]") {
  VehicleParams p;
  p.model = VehicleModel::DoubleIntegrator;
  p.max_accel = 0.2;
  p.max_speed = 1.0;
  p.seconds_per_model_time = 0.5;  // h = 0.5 s per step of dt = 1
  VehicleState s = vehicle_start(Vec2(-6, 3), 0.0);
  const Vec2 goal(2, -1);
  double worst = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const Vec2 v0 = s.velocity;
    const Vec2 x0 = s.x;
    drive(p, s, {x0 + 0.5 * (goal - x0), 0.5 * (goal - x0)}, 1.0, 1000.0);  // a P law, gain 0.5
    worst = std::max(worst, (s.velocity - v0).norm() / 0.5);
    // Constant acceleration over the step: the point moves by h times the mean velocity.
    CHECK((s.x - x0 - 0.25 * (v0 + s.velocity)).norm() < 1e-12);
  }
  CHECK(worst <= p.max_accel * (1 + kUlps));
  CHECK(worst == Approx(p.max_accel));  // it did bind
  CHECK((s.x - goal).norm() < 1e-9);    // the law's fixed point, delayed, not moved
  CHECK(s.velocity.norm() < 1e-9);
}

TEST_CASE("vehicle: the integrator model returns the law's step bit for bit", "[vehicle]") {
  std::mt19937_64 rng(5);
  const VehicleParams p;  // the default: integrator, no limit
  REQUIRE(moves_as_law(p));
  for (int trial = 0; trial < 1000; ++trial) {
    VehicleState s = vehicle_start(random_vec(rng, 10.0), 0.0);
    const StepResult law{random_vec(rng, 10.0), random_vec(rng, 1.0), trial % 7 == 0};
    const StepResult r = drive(p, s, law, 1.0, 1000.0);
    CHECK(r.x == law.x);
    CHECK(r.v == law.v);
    CHECK(r.clamped == law.clamped);
    CHECK(s.x == law.x);
  }
  // Swarms of either law and integrator, with the integrator model set, step exactly as agent_step.
  for (Law law : {Law::Paper, Law::Arc}) {
    for (Integrator integ : {Integrator::Euler, Integrator::RK4}) {
      Command c;
      c.law = law;
      c.integrator = integ;
      c.shape.kind = ShapeKind::Circle;
      c.shape.r0 = 4;
      const CompiledCommand cmd = compile(c);
      std::vector<Vec2> x = uniform_start(7, 4);
      Swarm swarm(cmd, x);
      swarm.set_vehicle(p, start_headings(p, 7, 4));
      CHECK(swarm.vehicles().empty());
      for (int k = 0; k < 40; ++k) {
        std::vector<Vec2> next(x.size());
        for (int i = 0; i < 7; ++i) {
          std::vector<Neighbour> nbrs;
          for (int j = 0; j < 7; ++j)
            if (j != i)
              nbrs.push_back({j, x[j],
                              law == Law::Arc ? closest_point(shape_at(cmd, k), cmd.curve(), x[j]).s
                                              : std::numeric_limits<double>::quiet_NaN()});
          next[i] = agent_step(cmd, i, x[i], nbrs, k * cmd.dt).x;
        }
        x = next;
        swarm.step();
      }
      INFO(to_string(law) << " " << to_string(integ));
      for (int i = 0; i < 7; ++i) CHECK(swarm.positions()[i] == x[i]);
    }
  }
}

TEST_CASE("vehicle: start headings are seeded per agent, within the spread", "[vehicle]") {
  VehicleParams p;
  p.initial_heading = 1.0;
  CHECK(start_heading(p, 3, 9) == 1.0);  // no spread: the heading itself
  p.heading_spread = 0.5;
  const auto h = start_headings(p, 50, 9);
  for (int i = 0; i < 50; ++i) {
    CHECK(std::abs(h[i] - 1.0) <= 0.5);
    CHECK(start_heading(p, i, 9) == h[i]);  // the same whatever the swarm's size
  }
  CHECK(start_headings(p, 50, 10) != h);
  // A held vehicle stops; a step of zero then leaves every model where it is.
  for (VehicleModel m : {VehicleModel::DoubleIntegrator, VehicleModel::Unicycle}) {
    VehicleParams q;
    q.model = m;
    VehicleState s = vehicle_start(Vec2(1, 1), 0.2);
    s.velocity = Vec2(0.3, 0.1);
    stop(s);
    drive(q, s, {s.x, Vec2::Zero()}, 1.0, 1000.0);
    CHECK(s.x == Vec2(1, 1));
  }
}

TEST_CASE("vehicle: a vehicle that would leave the workspace stops at its edge", "[vehicle]") {
  VehicleParams p;
  p.model = VehicleModel::DoubleIntegrator;
  VehicleState s = vehicle_start(Vec2(9.5, 0), 0.0);
  s.velocity = Vec2(3, 0);  // coasting toward the edge at 10
  const StepResult r = drive(p, s, {s.x, Vec2::Zero()}, 1.0, 10.0);
  CHECK(r.clamped);
  CHECK(s.x.x() <= 10.0);
}
