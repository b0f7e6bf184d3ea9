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

// --- The command to an external vehicle (vehicle_command) and the simulated body (body_step) ---

namespace {

/// v in the frame turned by angle, written out (not the code's rotate).
Vec2 turned(double angle, const Vec2& v) {
  return {std::cos(angle) * v.x() - std::sin(angle) * v.y(),
          std::sin(angle) * v.x() + std::cos(angle) * v.y()};
}

Vec2 linear(const Twist& t) { return {t.vx, t.vy}; }

/// A measured state: point, heading in [-pi, pi], and a last command within max_speed.
VehicleState random_state(const VehicleParams& p, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  VehicleState s = vehicle_start(random_vec(rng, 10.0), angle(rng));
  const Vec2 v0 = random_vec(rng, 1.0);
  s.velocity = p.max_speed > 0 && v0.norm() > p.max_speed ? Vec2(v0 * (p.max_speed / v0.norm())) : v0;
  return s;
}

}  // namespace

TEST_CASE("vehicle_command: the holonomic models' command, exactly", "[vehicle][command]") {
  VehicleParams p;
  p.seconds_per_model_time = 0.5;  // h = 0.25 s for dt = 0.5
  VehicleState s = vehicle_start(Vec2(1, 2), 0.7);
  s.velocity = Vec2(0.3, -0.2);
  const Vec2 law_x(1.2, 1.9);  // a step of (0.2, -0.1) in 0.25 s: (0.8, -0.4) m/s
  const Vec2 u(0.8, -0.4);
  for (VehicleModel m : {VehicleModel::Integrator, VehicleModel::DoubleIntegrator}) {
    p.model = m;
    INFO(to_string(m));
    // No limit: the law's velocity, turned into the body frame.
    VehicleCommand c = vehicle_command(p, s, law_x, 0.5, 0.1);
    CHECK((c.world - u).norm() < 1e-14);
    CHECK(!c.saturated);
    CHECK((linear(c.twist) - turned(-0.7, c.world)).norm() < 1e-15);
    CHECK(c.twist.wz == 0.0);
    CHECK((turned(0.7, linear(c.twist)) - c.world).norm() < 1e-15);
    // A speed limit shortens it, direction kept.
    p.max_speed = 0.5;
    c = vehicle_command(p, s, law_x, 0.5, 0.1);
    CHECK((c.world - 0.5 * u.normalized()).norm() < 1e-15);
    CHECK(c.saturated);
    CHECK(linear(c.twist).norm() == Approx(0.5));
    p.max_speed = 0.0;
  }
  // The double integrator's acceleration limit: from the last command toward the law's, by
  // max_accel * period_s.
  p.model = VehicleModel::DoubleIntegrator;
  p.max_accel = 2.0;
  const VehicleCommand c = vehicle_command(p, s, law_x, 0.5, 0.1);
  const Vec2 dv = u - s.velocity;
  CHECK((c.world - (s.velocity + 0.2 * dv.normalized())).norm() < 1e-15);
  CHECK(c.saturated);
  // Within reach (|dv| = 0.54 < 2 * 0.3): the law's velocity, not saturated.
  CHECK((vehicle_command(p, s, law_x, 0.5, 0.3).world - u).norm() < 1e-15);
  CHECK(!vehicle_command(p, s, law_x, 0.5, 0.3).saturated);
  // At rest on the law's position: a zero command.
  s.velocity = Vec2::Zero();
  const VehicleCommand rest = vehicle_command(p, s, s.x, 0.5, 0.1);
  CHECK(rest.world == Vec2::Zero());
  CHECK(linear(rest.twist) == Vec2::Zero());
  CHECK(!rest.saturated);
}

TEST_CASE("vehicle_command: the unicycle's command and its point's velocity", "[vehicle][command]") {
  std::mt19937_64 rng(13);
  for (int trial = 0; trial < 3000; ++trial) {
    const VehicleParams p = random_params(VehicleModel::Unicycle, rng);
    const VehicleState s = random_state(p, rng);
    const double dt = trial % 2 ? 1.0 : 0.3;
    const double h = dt * p.seconds_per_model_time;
    const Vec2 law_x = s.x + random_vec(rng, trial % 3 ? 0.1 : 3.0);
    const VehicleCommand c = vehicle_command(p, s, law_x, dt, 0.05);
    INFO("trial " << trial);
    // The twist is unicycle_command's, bit for bit.
    const UnicycleCommand u = unicycle_command(p, s.heading, law_x - s.x, h);
    CHECK(c.twist.vx == u.v);
    CHECK(c.twist.vy == 0.0);
    CHECK(c.twist.wz == u.w);
    // world is the point's velocity at the start of the motion: the central difference of its motion
    // over +-tau, a small fraction of a turn (from the origin, where rounding is least).
    const double tau = 1e-5 * std::min(h, 1.0 / (1.0 + std::abs(u.w)));
    VehicleState ahead = vehicle_start(Vec2::Zero(), s.heading), back = ahead;
    unicycle_move(p, ahead, u, tau);
    unicycle_move(p, back, u, -tau);
    CHECK((c.world - (ahead.x - back.x) / (2 * tau)).norm() <= 1e-7 * (1.0 + c.world.norm()));
    // Saturated exactly when the limits changed the command.
    VehicleParams free = p;
    free.max_speed = free.max_yaw_rate = 0.0;
    const UnicycleCommand w = unicycle_command(free, s.heading, law_x - s.x, h);
    CHECK(c.saturated == (w.v != u.v || w.w != u.w));
    // Unsaturated exact steering: held over h, the twist takes the point to the law's position.
    if (!c.saturated && p.steering == Steering::Exact) {
      VehicleState end = s;
      unicycle_move(p, end, {c.twist.vx, c.twist.wz}, h);
      CHECK((end.x - law_x).norm() < 1e-12 * (1.0 + (law_x - s.x).norm() / h));
    }
  }
}

TEST_CASE("vehicle_command: no command ever exceeds a limit (random states and limits)",
          "[vehicle][command]") {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int saturated = 0;
  for (VehicleModel model :
       {VehicleModel::Integrator, VehicleModel::DoubleIntegrator, VehicleModel::Unicycle}) {
    for (int trial = 0; trial < 20000; ++trial) {
      const VehicleParams p = random_params(model, rng);
      const VehicleState s = random_state(p, rng);
      const double dt = trial % 3 == 0 ? 1.0 : 0.25;
      const double h = dt * p.seconds_per_model_time;
      const double period = 0.005 + 0.2 * unit(rng);
      const Vec2 law_x = s.x + random_vec(rng, trial % 2 ? 0.1 : 5.0);
      const VehicleCommand c = vehicle_command(p, s, law_x, dt, period);
      INFO("model " << to_string(model) << " trial " << trial);
      REQUIRE(c.world.allFinite());
      saturated += c.saturated;
      if (model == VehicleModel::Unicycle) {
        if (p.max_speed > 0) CHECK(std::abs(c.twist.vx) <= p.max_speed);
        if (p.max_yaw_rate > 0) CHECK(std::abs(c.twist.wz) <= p.max_yaw_rate);
        CHECK(c.twist.vy == 0.0);
        continue;
      }
      CHECK(c.twist.wz == 0.0);
      CHECK((turned(s.heading, linear(c.twist)) - c.world).norm() <= 1e-14 * (1.0 + c.world.norm()));
      if (p.max_speed > 0) CHECK(linear(c.twist).norm() <= p.max_speed * (1 + kUlps));
      if (p.max_speed > 0) CHECK(c.world.norm() <= p.max_speed * (1 + kUlps));
      if (model == VehicleModel::DoubleIntegrator && p.max_accel > 0)
        CHECK((c.world - s.velocity).norm() <= p.max_accel * period * (1 + kUlps));
      // Not saturated: the law's velocity, to rounding; saturated: not the law's velocity.
      const Vec2 wanted = (law_x - s.x) / h;
      if (c.saturated)
        CHECK((c.world - wanted).norm() > 1e-9 * wanted.norm());
      else
        CHECK((c.world - wanted).norm() <= 1e-12 * (1.0 + wanted.norm()));
    }
  }
  CHECK(saturated > 10000);  // the limits did bind, often
}

TEST_CASE("vehicle_command: non-finite inputs give a zero command, saturated", "[vehicle][command]") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (VehicleModel m : {VehicleModel::Integrator, VehicleModel::DoubleIntegrator, VehicleModel::Unicycle}) {
    VehicleParams p;
    p.model = m;
    p.max_speed = 1.0;
    p.max_accel = 1.0;
    const VehicleState ok = vehicle_start(Vec2(1, 1), 0.3);
    const Vec2 law_x(1.5, 1.2);
    REQUIRE(vehicle_command(p, ok, law_x, 1.0, 0.1).world != Vec2::Zero());
    std::vector<VehicleCommand> bad;
    for (double x : {nan, inf}) {
      VehicleState s = ok;
      s.x.x() = x;
      bad.push_back(vehicle_command(p, s, law_x, 1.0, 0.1));
      s = ok;
      s.heading = x;
      bad.push_back(vehicle_command(p, s, law_x, 1.0, 0.1));
      s = ok;
      s.velocity.y() = x;
      bad.push_back(vehicle_command(p, s, law_x, 1.0, 0.1));
      bad.push_back(vehicle_command(p, ok, Vec2(1, x), 1.0, 0.1));
      bad.push_back(vehicle_command(p, ok, law_x, x, 0.1));
      bad.push_back(vehicle_command(p, ok, law_x, 1.0, x));
    }
    bad.push_back(vehicle_command(p, ok, law_x, 0.0, 0.1));   // no time to move in
    bad.push_back(vehicle_command(p, ok, law_x, 1.0, -1.0));  // nor until the next command
    for (const VehicleCommand& c : bad) {
      INFO(to_string(m));
      CHECK(c.twist.vx == 0.0);
      CHECK(c.twist.vy == 0.0);
      CHECK(c.twist.wz == 0.0);
      CHECK(c.world == Vec2::Zero());
      CHECK(c.saturated);
    }
  }
}

TEST_CASE("body: controlled_point and base_of", "[vehicle][body]") {
  VehicleParams p;
  p.offset = 0.3;
  CHECK(controlled_point(p, Vec2(1, 2), 0.5) == Vec2(1, 2));
  CHECK(base_of(p, Vec2(1, 2), 0.5) == Vec2(1, 2));
  p.model = VehicleModel::Unicycle;
  CHECK((controlled_point(p, Vec2(1, 2), kPi / 2) - Vec2(1, 2.3)).norm() < 1e-15);
  CHECK((base_of(p, Vec2(1, 2.3), kPi / 2) - Vec2(1, 2)).norm() < 1e-15);
  const VehicleState s = vehicle_start(Vec2(-3, 4), 2.0);
  CHECK(base_of(p, s.x, s.heading) == axle(p, s));
  CHECK((controlled_point(p, base_of(p, s.x, s.heading), s.heading) - s.x).norm() < 1e-15);
}

TEST_CASE("body: a unicycle taking its command at once runs unicycle_move's arc, to the bit",
          "[vehicle][body]") {
  std::mt19937_64 rng(19);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const BodyParams now{0.0};
  for (int trial = 0; trial < 5000; ++trial) {
    VehicleParams p = random_params(VehicleModel::Unicycle, rng);
    p.max_speed = p.max_yaw_rate = 0.0;
    VehicleState s = random_state(p, rng);
    Body body;
    body.base = base_of(p, s.x, s.heading);
    body.heading = s.heading;
    const UnicycleCommand c{random_vec(rng, 1.0).x(), trial % 5 == 0 ? 0.0 : 3.0 * (unit(rng) - 0.5)};
    const double h = 0.01 + unit(rng);
    body_step(p, now, body, {c.v, 0.0, c.w}, h);
    unicycle_move(p, s, c, h);
    INFO("trial " << trial);
    CHECK(controlled_point(p, body.base, body.heading) == s.x);
    CHECK(body.heading == s.heading);
    CHECK(body.actual.vx == c.v);
    CHECK(body.actual.wz == c.w);
  }
}

TEST_CASE("body: the first-order lag", "[vehicle][body]") {
  const double tau = 0.2, h = 0.05;
  const Twist cmd{0.4, -0.3, 0.7};
  for (VehicleModel m : {VehicleModel::Integrator, VehicleModel::DoubleIntegrator, VehicleModel::Unicycle}) {
    VehicleParams p;
    p.model = m;
    Body body;
    body.heading = 0.4;
    body_step(p, BodyParams{tau}, body, cmd, h);
    const double k1 = 1.0 - std::exp(-h / tau);
    INFO(to_string(m));
    CHECK(body.actual.vx == Approx(k1 * cmd.vx).epsilon(1e-14));
    CHECK(body.actual.vy == Approx(m == VehicleModel::Unicycle ? 0.0 : k1 * cmd.vy).epsilon(1e-14));
    CHECK(body.actual.wz == Approx(k1 * cmd.wz).epsilon(1e-14));
    // Steps compose as the continuous lag: after n steps, 1 - exp(-n h / tau) of the way.
    for (int n = 2; n <= 10; ++n) body_step(p, BodyParams{tau}, body, cmd, h);
    const double k10 = 1.0 - std::exp(-10 * h / tau);
    CHECK(body.actual.vx == Approx(k10 * cmd.vx).epsilon(1e-13));
    CHECK(body.actual.wz == Approx(k10 * cmd.wz).epsilon(1e-13));
  }
}

TEST_CASE("body: a holonomic body moves exactly for a constant body velocity and yaw rate",
          "[vehicle][body]") {
  VehicleParams p;
  p.model = VehicleModel::DoubleIntegrator;
  Body body;
  body.base = Vec2(1, -2);
  body.heading = 2.9;
  const Twist c{0.6, -0.4, 1.3};
  const Body start = body;
  body.actual = c;  // already moving with it: the lag leaves it
  body_step(p, BodyParams{0.1}, body, c, 1.5);
  CHECK(body.heading == Approx(std::remainder(2.9 + 1.3 * 1.5, 2 * kPi)));
  CHECK(std::abs(body.heading) <= kPi);
  // The integral of R(heading(t)) (vx, vy) over the step, by many midpoint sub-steps.
  Vec2 b = start.base;
  double th = start.heading;
  const int k = 100000;
  const double dh = 1.5 / k;
  for (int i = 0; i < k; ++i) {
    b += dh * turned(th + 0.5 * c.wz * dh, linear(c));
    th += c.wz * dh;
  }
  CHECK((body.base - b).norm() < 1e-9);
  // Without a turn: straight along the heading.
  body = start;
  body_step(p, BodyParams{0.0}, body, {0.6, -0.4, 0.0}, 1.5);
  CHECK((body.base - (start.base + 1.5 * turned(2.9, Vec2(0.6, -0.4)))).norm() < 1e-15);
}

TEST_CASE("body: a unicycle body ignores vy", "[vehicle][body]") {
  VehicleParams p;
  p.model = VehicleModel::Unicycle;
  Body a, b;
  a.heading = b.heading = 0.8;
  for (int k = 0; k < 20; ++k) {
    body_step(p, BodyParams{0.1}, a, {0.5, 0.0, 0.3}, 0.05);
    body_step(p, BodyParams{0.1}, b, {0.5, 2.0, 0.3}, 0.05);
  }
  CHECK(a.base == b.base);
  CHECK(a.heading == b.heading);
  CHECK(b.actual.vy == 0.0);
  // A sideways command alone leaves it where it is.
  Body c;
  body_step(p, BodyParams{0.0}, c, {0.0, 1.0, 0.0}, 1.0);
  CHECK(c.base == Vec2::Zero());
}

TEST_CASE("body: no motion ever exceeds a limit (random bodies, commands and limits)", "[vehicle][body]") {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  for (VehicleModel model :
       {VehicleModel::Integrator, VehicleModel::DoubleIntegrator, VehicleModel::Unicycle}) {
    int accel_bound = 0;
    for (int trial = 0; trial < 20000; ++trial) {
      const VehicleParams p = random_params(model, rng);
      const BodyParams b{trial % 4 == 0 ? 0.0 : 0.3 * unit(rng)};
      Body body;
      body.base = random_vec(rng, 10.0);
      body.heading = angle(rng);
      // A body that moved within its limits before.
      body_step(p, BodyParams{0.0}, body,
                {2 * random_vec(rng, 1.0).x(), random_vec(rng, 1.0).x(), angle(rng)}, 0.01);
      const Body before = body;
      const Twist cmd{3 * random_vec(rng, 1.0).x(), 3 * random_vec(rng, 1.0).x(), 3 * angle(rng)};
      const double h = 0.005 + 0.3 * unit(rng);
      body_step(p, b, body, cmd, h);
      INFO("model " << to_string(model) << " trial " << trial);
      REQUIRE(body.base.allFinite());
      CHECK(std::abs(body.heading) <= kPi);
      const Twist& a = body.actual;
      if (model == VehicleModel::Unicycle) {
        CHECK(a.vy == 0.0);
        if (p.max_speed > 0) CHECK(std::abs(a.vx) <= p.max_speed);
        if (p.max_yaw_rate > 0) CHECK(std::abs(a.wz) <= p.max_yaw_rate);
        // It moved along the arc of its actual command.
        VehicleState s = vehicle_start(controlled_point(p, before.base, before.heading), before.heading);
        unicycle_move(p, s, {a.vx, a.wz}, h);
        CHECK((controlled_point(p, body.base, body.heading) - s.x).norm() <
              1e-13);  // the round trip's rounding
        continue;
      }
      if (p.max_speed > 0) CHECK(linear(a).norm() <= p.max_speed * (1 + kUlps));
      // It moved by at most its speed times h.
      CHECK((body.base - before.base).norm() <= linear(a).norm() * h * (1 + kUlps) + 1e-14);
      if (model == VehicleModel::DoubleIntegrator && p.max_accel > 0) {
        const double dv = (linear(a) - linear(before.actual)).norm();
        CHECK(dv <= p.max_accel * h * (1 + kUlps));
        accel_bound += dv >= p.max_accel * h * (1 - kUlps);
      }
    }
    if (model == VehicleModel::DoubleIntegrator) CHECK(accel_bound > 1000);
  }
}

TEST_CASE("body: an agent's loop drives a lagging unicycle to its goal", "[vehicle][body]") {
  // The agent: every period it measures the body's controlled point, commands toward the law's new
  // position (here the goal itself), and records the command; the simulator integrates the body.
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  VehicleParams p;
  p.model = VehicleModel::Unicycle;
  p.max_speed = 0.5;
  p.max_yaw_rate = 1.0;
  p.offset = 0.2;
  const double period = 0.05;
  p.seconds_per_model_time = period;  // h = period for dt = 1
  const BodyParams b{0.05};
  const Vec2 goal(1.0, -0.5);
  for (int trial = 0; trial < 50; ++trial) {
    Body body;
    body.base = random_vec(rng, 2.0);
    body.heading = angle(rng);
    Vec2 last = Vec2::Zero();
    int saturated = 0;
    for (int k = 0; k < 1200; ++k) {  // 60 s
      VehicleState s = vehicle_start(controlled_point(p, body.base, body.heading), body.heading);
      s.velocity = last;
      const VehicleCommand c = vehicle_command(p, s, goal, 1.0, period);
      saturated += c.saturated;
      last = c.world;
      body_step(p, b, body, c.twist, period);
    }
    INFO("trial " << trial);
    CHECK((controlled_point(p, body.base, body.heading) - goal).norm() < 1e-3);
    CHECK(saturated > 0);  // the limits bound on the way
  }
}
