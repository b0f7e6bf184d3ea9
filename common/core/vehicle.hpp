#pragma once
/// Vehicle models: what an agent drives. The law (core::agent_step, core::agent_steps) gives the step
/// the agent should take; the vehicle turns it into motion within its limits (drive). The simulator
/// (core::Swarm) and the agent's logic (agent::AgentLogic) both call drive on the law's step, so they
/// compute the same numbers.
///
/// Units: shape units are metres. One unit of the law's model time is `seconds_per_model_time` seconds
/// of the vehicle's time: a law step of dt lasts h = dt * seconds_per_model_time seconds, and the limits
/// are in m/s, rad/s and m/s^2 of that time. The agent's published position is its vehicle's
/// controlled point (VehicleState::x): the vehicle itself for the integrator models, the point `offset`
/// ahead of the axle for the unicycle. The vehicle is the robot's own property (agent config), never
/// part of a command. docs/VEHICLES.md. Pure: Eigen and the standard library.
#include <cstdint>
#include <string_view>
#include <vector>

#include "law.hpp"
#include "types.hpp"

namespace shapeform::core {

/// What an agent drives.
enum class VehicleModel {
  Integrator,        ///< the point moves as the law steps it (without max_speed: bit for bit the law's step)
  DoubleIntegrator,  ///< a point mass: its velocity follows the law's, its acceleration bounded
  Unicycle  ///< a differential drive (forward speed v, yaw rate w) steered by a point ahead of its axle
};
std::string_view to_string(VehicleModel m);
bool parse_vehicle_model(std::string_view name, VehicleModel& out);

/// How a unicycle chooses the (v, w) it holds over a step.
enum class Steering {
  Exact,      ///< the (v, w) whose arc carries the point exactly along the law's step (sampled-data
              ///< linearisation)
  Linearised  ///< the classic feedback linearisation [v; offset w] = R(-heading) u, u the law's velocity
};
std::string_view to_string(Steering s);
bool parse_steering(std::string_view name, Steering& out);

/// A vehicle's model and limits. A limit of 0 is no limit.
struct VehicleParams {
  VehicleModel model = VehicleModel::Integrator;
  Steering steering = Steering::Exact;  ///< unicycle only
  /// m/s: the point's speed (integrator, double integrator), the forward speed |v| (unicycle)
  double max_speed = 0.0;
  double max_yaw_rate = 0.0;            ///< rad/s, unicycle: |w|
  double max_accel = 0.0;               ///< m/s^2, double integrator: |dv/dt| (a unicycle is kinematic)
  double offset = 0.2;                  ///< m, unicycle: how far ahead of the axle the controlled point is
  double seconds_per_model_time = 1.0;  ///< s of vehicle time per unit of the law's model time
  double initial_heading = 0.0;         ///< rad, counter-clockwise from the x1 axis
  double heading_spread = 0.0;  ///< rad: start headings uniform in initial_heading +- this (seeded per agent)
};

/// One vehicle's state.
struct VehicleState {
  Vec2 x = Vec2::Zero();  ///< the controlled point, m: the agent's published position
  double heading = 0.0;   ///< rad in [-pi, pi]; only the unicycle turns
  /// m/s: the point's velocity at the end of the last step (the double integrator's state), its mean
  /// over the last step for the other models
  Vec2 velocity = Vec2::Zero();
  double speed = 0.0;     ///< unicycle: the forward speed v held over the last step, m/s
  double yaw_rate = 0.0;  ///< unicycle: the yaw rate w held over the last step, rad/s
};

/// Whether the vehicle moves exactly as the law steps it (the integrator without max_speed): drive then
/// returns the law's step bit for bit.
bool moves_as_law(const VehicleParams& p);

/// Agent id's start heading: initial_heading plus a uniform draw in [-heading_spread, heading_spread]
/// seeded by (seed, id) alone, so the simulator and every process hosting the agent agree.
double start_heading(const VehicleParams& p, std::int32_t id, std::uint64_t seed);
/// start_heading of agents 0..n-1.
std::vector<double> start_headings(const VehicleParams& p, int n, std::uint64_t seed);

/// A vehicle at rest whose controlled point is x.
VehicleState vehicle_start(const Vec2& x, double heading);

/// Unit vector of a heading.
Vec2 heading_vector(double heading);

/// The unicycle's axle centre: `offset` behind the controlled point along the heading.
Vec2 axle(const VehicleParams& p, const VehicleState& s);

/// One step: the vehicle at s (s.x the position the law stepped from) moves over dt model time toward
/// the law's new position law.x, within its limits. Returns what the agent publishes: the new point,
/// its velocity over the step in shape units per model time ((x_new - x) / dt, as agent_step's), and
/// whether the step was clamped (the law's, or the vehicle's own: a point that would leave the workspace
/// is stopped at its edge; a non-finite motion is not taken and the vehicle stops).
StepResult drive(const VehicleParams& p, VehicleState& s, const StepResult& law, double dt, double workspace);

/// Stops the vehicle where it is (a held command: no step is taken to brake over).
void stop(VehicleState& s);

/// A double integrator braking as hard as it may: each step of h s shortens its velocity by max_accel h
/// (to 0 when shorter; to 0 at once when max_accel <= 0) and moves its point by h (v0 + v1) / 2, as
/// drive does. braking_velocity is the velocity one such step leaves; braking_displacement is where
/// the point stops, relative to where it is, along v: its braking segment is [x, x + that].
Vec2 braking_velocity(const Vec2& v, double max_accel, double h);
Vec2 braking_displacement(const Vec2& v, double max_accel, double h);
/// Its length from speed u: how far braking from u takes the point (infinite for an infinite u).
double braking_distance(double u, double max_accel, double h);
/// A bound on |braking_displacement(v1) - braking_displacement(v0)| / |v1 - v0| for speeds up to
/// max_speed: max_speed / max_accel + h / 2 (h / 2 without an acceleration limit).
double braking_lipschitz(double max_speed, double max_accel, double h);
/// How far the ends of a double integrator's braking segment [x, x + braking_displacement(v)] may move
/// in `steps` steps of h s (fractional: linear between whole steps, as a margin of speed times age is)
/// from a velocity of speed at most `speed`: its speed after i steps is at most s_i = min(max_speed,
/// speed + i max_accel h), its point moves at most h (s_i + s_(i+1)) / 2 per step, and its braking
/// displacement changes by at most braking_lipschitz(s_k) min(k max_accel h, s_k + speed), and never by
/// more than braking_distance(s_k) + braking_distance(speed). From max_speed that is steps (2 max_speed +
/// max_accel h / 2) h, the bound for a neighbour of unknown speed; a slow one's segment moves far less.
/// Infinite when the speed is unbounded (max_speed infinite and no acceleration limit).
double braking_reach(double speed, double steps, double max_speed, double max_accel, double h);

/// A unicycle's command: forward speed v (m/s, negative = backwards) and yaw rate w (rad/s).
struct UnicycleCommand {
  double v = 0.0;
  double w = 0.0;
};

/// The command a unicycle at `heading` holds for h seconds to move its controlled point by `step`
/// (m, world frame), within max_speed and max_yaw_rate. Exact steering: unlimited, the point ends
/// exactly at +step; when a limit binds, at +s step with s in (0, 1) the largest fraction found whose
/// command is within the limits (so the point keeps the step's direction). Linearised: (v, w) of the
/// classic law for u = step / h, scaled together by the one factor that brings both within the limits.
UnicycleCommand unicycle_command(const VehicleParams& p, double heading, const Vec2& step, double h);

/// The unicycle holding c for h seconds: its axle runs the arc of radius v / w exactly.
void unicycle_move(const VehicleParams& p, VehicleState& s, const UnicycleCommand& c, double h);

// --- An external vehicle: the command an agent sends, and the body a vehicle simulator integrates ---

/// A velocity command as a robot takes it (ROS REP 103, geometry_msgs/Twist's linear.x, linear.y and
/// angular.z): in the body frame (x forward along the heading, y to the left), m/s and rad/s.
struct Twist {
  double vx = 0.0, vy = 0.0, wz = 0.0;
};

/// What an agent commands its external vehicle for the next period.
struct VehicleCommand {
  Twist twist;                ///< the command as sent, body frame
  Vec2 world = Vec2::Zero();  ///< the same command: the controlled point's velocity, world frame, m/s
  bool saturated = false;     ///< a limit cut the wanted command (the vehicle cannot follow the law)
};

/// The command that moves the controlled point s.x toward the law's new position law_x over one law
/// step of h = dt * seconds_per_model_time seconds, within the vehicle's limits. s is measured: s.x the
/// controlled point (controlled_point of the robot's pose), s.heading its heading; s.velocity is the
/// last command's `world` (the double integrator's state: the caller sets s.velocity = c.world once c is
/// published). period_s is the time until the next command (the agent's loop period).
/// - integrator: world = (law_x - s.x) / h, shortened to max_speed (direction kept); wz = 0.
/// - double integrator: world moves from s.velocity toward (law_x - s.x) / h (shortened to max_speed)
///   by at most max_accel * period_s (the limit between successive commands); wz = 0. s.velocity is
///   expected within max_speed (it was a command): max_speed is kept first.
/// - unicycle: (vx, wz) = unicycle_command(p, s.heading, law_x - s.x, h), vy = 0; world is the
///   point's velocity at the start of that motion, R(heading) (v, offset w).
/// For the holonomic models twist = R(-heading) world. No command exceeds max_speed (|(vx, vy)| to
/// rounding; the unicycle's |vx| exactly), max_yaw_rate (|wz|, unicycle) or max_accel (|world -
/// s.velocity| <= max_accel period_s to rounding, double integrator). saturated is exact: true when a
/// limit bound, not from rounding. Non-finite inputs, or h or period_s not positive, give the zero
/// command with saturated = true (the vehicle is told to stop, whatever its acceleration limit).
VehicleCommand vehicle_command(const VehicleParams& p, const VehicleState& s, const Vec2& law_x, double dt,
                               double period_s);

/// A simulated robot body's response.
struct BodyParams {
  double response_s = 0.1;  ///< s: first-order lag time constant of the wheels/motors; 0: the command at once
};

/// A simulated robot body: what the vehicle simulator integrates.
struct Body {
  Vec2 base = Vec2::Zero();  ///< m: the robot's pose position (the axle centre of a unicycle, the body else)
  double heading = 0.0;      ///< rad in [-pi, pi]
  Twist actual;              ///< the velocity it moves with now, body frame
};

/// The body over h seconds under `command`. Its velocity first: actual moves toward the command by the
/// first-order lag, the factor 1 - exp(-h / response_s) on every component (the command itself when
/// response_s is 0). Then the model's limits cut it: the holonomic models (integrator, double
/// integrator) keep |(vx, vy)| <= max_speed and, the double integrator, |change of (vx, vy)| <=
/// max_accel h from the previous actual (their wz is not limited); a unicycle drops vy (it cannot move
/// sideways) and clamps |vx| <= max_speed, |wz| <= max_yaw_rate. Then it moves, holding actual over the
/// whole h. The motion is exact for a constant body-frame velocity and yaw rate: the base runs an arc,
/// moving by h sinc(wz h / 2) R(heading + wz h / 2) (vx, vy) (a unicycle's is unicycle_move's arc, to
/// the bit), and heading += wz h, wrapped to [-pi, pi]. A non-finite command is taken as zero (a driver
/// rejects it); an h not positive or not finite does nothing.
void body_step(const VehicleParams& p, const BodyParams& b, Body& body, const Twist& command, double h);

/// The controlled point of a robot whose pose is (base, heading): `offset` ahead of a unicycle's axle,
/// the base itself for the other models.
Vec2 controlled_point(const VehicleParams& p, const Vec2& base, double heading);
/// Its inverse: the pose position whose controlled point is `point`.
Vec2 base_of(const VehicleParams& p, const Vec2& point, double heading);

}  // namespace shapeform::core
