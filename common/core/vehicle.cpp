#include "vehicle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "envelope.hpp"

namespace shapeform::core {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// v shortened to length `limit` when longer (direction kept); limit 0: no limit.
Vec2 saturate(const Vec2& v, double limit) {
  if (limit <= 0.0) return v;
  const double n = v.norm();
  return n > limit ? Vec2(v * (limit / n)) : v;
}

/// sin(x) / x, 1 at 0.
double sinc(double x) { return std::abs(x) < 1e-4 ? 1.0 - x * x / 6.0 : std::sin(x) / x; }

/// v in the frame turned by `angle`.
Vec2 rotate(double angle, const Vec2& v) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

/// The unicycle's command that moves its point by b (body frame, m) in h seconds exactly. With the axle
/// on an arc of angle 2a, the point moves by L (cos a, sin a) + 2 offset sin a (-sin a, cos a), L the
/// arc's chord; projected on (-sin a, cos a) that gives tan a = b_y / (b_x + 2 offset), on (cos a, sin a)
/// L = b_x cos a + b_y sin a. a is taken in [-pi/2, pi/2] (v < 0 reverses), and L = v h sinc(a).
UnicycleCommand exact_command(double offset, const Vec2& b, double h) {
  const double den = b.x() + 2.0 * offset;
  const double a = den >= 0.0 ? std::atan2(b.y(), den) : std::atan2(-b.y(), -den);
  const double chord = b.x() * std::cos(a) + b.y() * std::sin(a);
  return {chord / (h * sinc(a)), 2.0 * a / h};
}

/// A unicycle's arc: holding forward speed v and yaw rate w for h seconds from `heading`, its axle moves
/// by the chord of length v h sinc(w h / 2), along the heading half-way through the turn.
Vec2 arc_chord(double heading, double v, double w, double h) {
  const double turn = w * h;
  return (v * h * sinc(0.5 * turn)) * heading_vector(heading + 0.5 * turn);
}

bool finite(const Twist& t) { return std::isfinite(t.vx) && std::isfinite(t.vy) && std::isfinite(t.wz); }

/// The stop command of vehicle_command: what it sends for inputs it cannot use.
VehicleCommand stop_command() {
  VehicleCommand c;
  c.saturated = true;
  return c;
}

bool within(const VehicleParams& p, const UnicycleCommand& c) {
  return (p.max_speed <= 0.0 || std::abs(c.v) <= p.max_speed) &&
         (p.max_yaw_rate <= 0.0 || std::abs(c.w) <= p.max_yaw_rate);
}

/// The classic law's command for u = b / h, both scaled by the one factor that brings them within the
/// limits (the direction of the point's velocity at the step's start is kept).
UnicycleCommand linearised_command(const VehicleParams& p, const Vec2& b, double h) {
  UnicycleCommand c{b.x() / h, b.y() / (p.offset * h)};
  if (within(p, c)) return c;
  double k = 1.0;
  if (p.max_speed > 0.0 && std::abs(c.v) > p.max_speed) k = std::min(k, p.max_speed / std::abs(c.v));
  if (p.max_yaw_rate > 0.0 && std::abs(c.w) > p.max_yaw_rate) k = std::min(k, p.max_yaw_rate / std::abs(c.w));
  c = {k * c.v, k * c.w};
  // k's rounding may leave one an ulp over its limit.
  if (p.max_speed > 0.0) c.v = std::clamp(c.v, -p.max_speed, p.max_speed);
  if (p.max_yaw_rate > 0.0) c.w = std::clamp(c.w, -p.max_yaw_rate, p.max_yaw_rate);
  return c;
}

/// The double integrator over h: its velocity moves toward `wanted` (within max_speed) by at most
/// max_accel h, at constant acceleration, so the point moves by h (v0 + v1) / 2.
void accelerate(const VehicleParams& p, VehicleState& s, const Vec2& wanted, double h) {
  const Vec2 v0 = s.velocity;
  const Vec2 goal = saturate(wanted, p.max_speed);
  const Vec2 dv = p.max_accel > 0.0 ? saturate(goal - v0, p.max_accel * h) : Vec2(goal - v0);
  // Between v0 and goal, both within max_speed: the guard only removes rounding.
  const Vec2 v1 = saturate(v0 + dv, p.max_speed);
  s.x += (0.5 * h) * (v0 + v1);
  s.velocity = v1;
}

/// The integrator with max_speed: the law's position when it is within reach, else as far toward it.
void limit_step(const VehicleParams& p, VehicleState& s, const Vec2& target, double h) {
  const Vec2 step = target - s.x;
  s.velocity = saturate(step / h, p.max_speed);
  s.x = step.norm() <= p.max_speed * h ? target : Vec2(s.x + h * s.velocity);
}

/// What drive returns once the vehicle moved from `from`: a non-finite motion is undone (the vehicle
/// stops), a point outside the workspace is stopped at its edge.
StepResult settle(VehicleState& s, const VehicleState& before, double dt, double h, double workspace,
                  bool clamped) {
  if (!s.x.allFinite() || !s.velocity.allFinite() || !std::isfinite(s.heading)) {
    s = before;
    stop(s);
    return {s.x, Vec2::Zero(), true};
  }
  bool out = false;
  const Vec2 inside = keep_inside(s.x, workspace, out);
  if (out) {
    s.x = inside;
    s.velocity = (inside - before.x) / h;
  }
  return {s.x, (s.x - before.x) / dt, clamped || out};
}

}  // namespace

bool moves_as_law(const VehicleParams& p) {
  return p.model == VehicleModel::Integrator && p.max_speed <= 0.0;
}

double start_heading(const VehicleParams& p, std::int32_t id, std::uint64_t seed) {
  if (p.heading_spread <= 0.0) return p.initial_heading;
  // Its own stream (not swarm.seed's uniform start), so positions do not depend on the vehicle.
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(id), 0x68656164u};
  std::mt19937_64 rng(seq);
  std::uniform_real_distribution<double> u(-p.heading_spread, p.heading_spread);
  return p.initial_heading + u(rng);
}

std::vector<double> start_headings(const VehicleParams& p, int n, std::uint64_t seed) {
  std::vector<double> out;
  for (int i = 0; i < n; ++i) out.push_back(start_heading(p, i, seed));
  return out;
}

VehicleState vehicle_start(const Vec2& x, double heading) {
  VehicleState s;
  s.x = x;
  s.heading = std::remainder(heading, 2.0 * kPi);
  return s;
}

Vec2 heading_vector(double heading) { return {std::cos(heading), std::sin(heading)}; }

Vec2 axle(const VehicleParams& p, const VehicleState& s) {
  return s.x - p.offset * heading_vector(s.heading);
}

void stop(VehicleState& s) {
  s.velocity = Vec2::Zero();
  s.speed = 0.0;
  s.yaw_rate = 0.0;
}

Vec2 braking_velocity(const Vec2& v, double max_accel, double h) {
  return max_accel > 0.0 ? Vec2(v - saturate(v, max_accel * h)) : Vec2::Zero();
}

double braking_distance(double u, double max_accel, double h) {
  if (!std::isfinite(u)) return std::numeric_limits<double>::infinity();
  // n whole steps at dv = a h, then one from the rest r to 0: h (n u - a h n^2 / 2) + h r / 2.
  const double dv = max_accel * h;
  const double n = max_accel > 0.0 ? std::floor(u / dv) : 0.0;
  const double r = u - n * dv;
  return h * (n * u - 0.5 * dv * n * n) + 0.5 * h * r;
}

Vec2 braking_displacement(const Vec2& v, double max_accel, double h) {
  const double u = v.norm();
  if (u == 0.0) return Vec2::Zero();
  return (braking_distance(u, max_accel, h) / u) * v;
}

double braking_lipschitz(double max_speed, double max_accel, double h) {
  return (max_accel > 0.0 ? max_speed / max_accel : 0.0) + 0.5 * h;
}

double braking_reach(double speed, double steps, double max_speed, double max_accel, double h) {
  if (!(steps > 0.0)) return 0.0;
  const double dv = max_accel > 0.0 ? max_accel * h : std::numeric_limits<double>::infinity();
  const double s0 = std::min(speed, max_speed);
  // Whole steps before the speed bound is reached (s_(i+1) = s0 + (i + 1) dv <= max_speed).
  const double rising = dv > 0.0 ? std::floor((max_speed - s0) / dv) : 0.0;
  const auto whole = [&](double k) {
    if (k <= 0.0) return 0.0;
    const double j = std::min(k, rising);
    double moved = j > 0.0 ? h * (j * s0 + 0.5 * dv * j * j) : 0.0;
    if (k > j) moved += 0.5 * h * (std::min(max_speed, s0 + j * dv) + max_speed) + (k - j - 1.0) * h * max_speed;
    const double sk = std::min(max_speed, s0 + k * dv);
    const double turned = std::min(braking_lipschitz(sk, max_accel, h) * std::min(k * dv, sk + s0),
                                   braking_distance(sk, max_accel, h) + braking_distance(s0, max_accel, h));
    return moved + turned;
  };
  const double k = std::floor(steps), frac = steps - k;
  const double r = whole(k);
  const double out = frac > 0.0 ? r + frac * (whole(k + 1.0) - r) : r;
  return std::isfinite(out) ? out : std::numeric_limits<double>::infinity();
}

UnicycleCommand unicycle_command(const VehicleParams& p, double heading, const Vec2& step, double h) {
  const Vec2 b = rotate(-heading, step);
  if (p.steering == Steering::Linearised) return linearised_command(p, b, h);
  UnicycleCommand c = exact_command(p.offset, b, h);
  if (within(p, c)) return c;
  // The largest fraction of the step the limits allow (bisection; 0 is always allowed).
  double lo = 0.0, hi = 1.0;
  c = {};
  for (int k = 0; k < 60 && hi - lo > 1e-15; ++k) {
    const double mid = 0.5 * (lo + hi);
    const UnicycleCommand m = exact_command(p.offset, mid * b, h);
    if (within(p, m)) {
      lo = mid;
      c = m;
    } else {
      hi = mid;
    }
  }
  return c;
}

void unicycle_move(const VehicleParams& p, VehicleState& s, const UnicycleCommand& c, double h) {
  const Vec2 from = s.x;
  const Vec2 a = axle(p, s) + arc_chord(s.heading, c.v, c.w, h);
  s.heading = std::remainder(s.heading + c.w * h, 2.0 * kPi);
  s.x = a + p.offset * heading_vector(s.heading);
  s.velocity = (s.x - from) / h;
  s.speed = c.v;
  s.yaw_rate = c.w;
}

StepResult drive(const VehicleParams& p, VehicleState& s, const StepResult& law, double dt,
                 double workspace) {
  if (moves_as_law(p)) {
    s.x = law.x;
    s.velocity = law.v / p.seconds_per_model_time;
    return law;
  }
  const double h = dt * p.seconds_per_model_time;
  const VehicleState before = s;
  switch (p.model) {
    case VehicleModel::Integrator:
      limit_step(p, s, law.x, h);
      break;
    case VehicleModel::DoubleIntegrator:
      accelerate(p, s, (law.x - s.x) / h, h);
      break;
    case VehicleModel::Unicycle:
      unicycle_move(p, s, unicycle_command(p, s.heading, law.x - s.x, h), h);
      break;
  }
  return settle(s, before, dt, h, workspace, law.clamped);
}

VehicleCommand vehicle_command(const VehicleParams& p, const VehicleState& s, const Vec2& law_x, double dt,
                               double period_s) {
  const double h = dt * p.seconds_per_model_time;
  if (!s.x.allFinite() || !std::isfinite(s.heading) || !s.velocity.allFinite() || !law_x.allFinite() ||
      !(std::isfinite(h) && h > 0.0) || !(std::isfinite(period_s) && period_s > 0.0))
    return stop_command();
  const Vec2 step = law_x - s.x;
  VehicleCommand c;
  if (p.model == VehicleModel::Unicycle) {
    const UnicycleCommand u = unicycle_command(p, s.heading, step, h);
    VehicleParams free = p;
    free.max_speed = free.max_yaw_rate = 0.0;
    const UnicycleCommand wanted = unicycle_command(free, s.heading, step, h);
    c.twist = {u.v, 0.0, u.w};
    c.world = rotate(s.heading, Vec2(u.v, p.offset * u.w));
    c.saturated = u.v != wanted.v || u.w != wanted.w;
  } else {
    const Vec2 wanted = step / h;
    c.world = saturate(wanted, p.max_speed);
    c.saturated = c.world != wanted;
    if (p.model == VehicleModel::DoubleIntegrator) {
      const Vec2 dv = c.world - s.velocity;
      const double reach = p.max_accel * period_s;
      c.saturated = c.saturated || (p.max_accel > 0.0 && dv.norm() > reach);
      // Between s.velocity and the goal, both within max_speed: the guard only removes rounding.
      c.world = saturate(s.velocity + (p.max_accel > 0.0 ? saturate(dv, reach) : dv), p.max_speed);
    }
    const Vec2 body = rotate(-s.heading, c.world);
    c.twist = {body.x(), body.y(), 0.0};
  }
  if (!c.world.allFinite() || !finite(c.twist)) return stop_command();
  return c;
}

void body_step(const VehicleParams& p, const BodyParams& b, Body& body, const Twist& command, double h) {
  if (!(std::isfinite(h) && h > 0.0)) return;
  const Twist cmd = finite(command) ? command : Twist{};
  Twist& a = body.actual;
  const Vec2 before(a.vx, a.vy);
  if (b.response_s > 0.0) {
    const double k = -std::expm1(-h / b.response_s);  // 1 - exp(-h / response_s)
    a = {a.vx + k * (cmd.vx - a.vx), a.vy + k * (cmd.vy - a.vy), a.wz + k * (cmd.wz - a.wz)};
  } else {
    a = cmd;
  }
  if (p.model == VehicleModel::Unicycle) {
    a.vy = 0.0;
    if (p.max_speed > 0.0) a.vx = std::clamp(a.vx, -p.max_speed, p.max_speed);
    if (p.max_yaw_rate > 0.0) a.wz = std::clamp(a.wz, -p.max_yaw_rate, p.max_yaw_rate);
    body.base += arc_chord(body.heading, a.vx, a.wz, h);
  } else {
    Vec2 v(a.vx, a.vy);
    if (p.model == VehicleModel::DoubleIntegrator && p.max_accel > 0.0)
      v = before + saturate(v - before, p.max_accel * h);
    // The projection on the speed limit's disc keeps the acceleration limit (before is within it).
    v = saturate(v, p.max_speed);
    a.vx = v.x();
    a.vy = v.y();
    const double turn = a.wz * h;
    body.base += (h * sinc(0.5 * turn)) * rotate(body.heading + 0.5 * turn, v);
  }
  body.heading = std::remainder(body.heading + a.wz * h, 2.0 * kPi);
}

Vec2 controlled_point(const VehicleParams& p, const Vec2& base, double heading) {
  return p.model == VehicleModel::Unicycle ? Vec2(base + p.offset * heading_vector(heading)) : base;
}

Vec2 base_of(const VehicleParams& p, const Vec2& point, double heading) {
  return p.model == VehicleModel::Unicycle ? Vec2(point - p.offset * heading_vector(heading)) : point;
}

}  // namespace shapeform::core
