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

}  // namespace shapeform::core
