#include "swarm.hpp"

#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include "envelope.hpp"

namespace shapeform::core {

std::vector<Vec2> uniform_start(int n, std::uint64_t seed, double half_width) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-half_width, half_width);
  std::vector<Vec2> x(static_cast<std::size_t>(std::max(n, 0)));
  for (Vec2& xi : x) {
    const double x1 = u(rng);
    const double x2 = u(rng);
    xi = Vec2(x1, x2);
  }
  return x;
}

Swarm::Swarm(CompiledCommand cmd, std::vector<Vec2> start)
    : x_(std::move(start)), next_(x_.size()), arc_(x_.size()), safety_state_(x_.size()), blocked_by_(x_.size(), -1) {
  nbrs_.reserve(x_.size());
  set_command(cmd);
}

void Swarm::set_command(const CompiledCommand& cmd) {
  cmd_ = cmd;
  zones_ = convex_pieces(cmd_.keep_out);
  safety_ = safety_params(cmd_, vehicle_);
}

bool batch_applies(const CompiledCommand& cmd, const VehicleParams& vehicle) {
  return cmd.law == Law::Paper && cmd.integrator == Integrator::Euler && vehicle.model == VehicleModel::Integrator &&
         !filters(cmd);
}

void Swarm::set_vehicle(const VehicleParams& p, const std::vector<double>& headings) {
  if (!headings.empty() && headings.size() != x_.size())
    throw std::invalid_argument("Swarm::set_vehicle: " + std::to_string(headings.size()) + " headings for " +
                                std::to_string(x_.size()) + " agents");
  vehicle_ = p;
  safety_ = safety_params(cmd_, vehicle_);
  vehicles_.clear();
  if (moves_as_law(p)) return;
  for (std::size_t i = 0; i < x_.size(); ++i)
    vehicles_.push_back(vehicle_start(x_[i], headings.empty() ? p.initial_heading : headings[i]));
}

Vec2 Swarm::move(int i, const StepResult& r) {
  if (vehicles_.empty()) return r.x;
  return drive(vehicle_, vehicles_[static_cast<std::size_t>(i)], r, cmd_.dt, cmd_.workspace).x;
}

Vec2 Swarm::move_safely(int i, const StepResult& r) {
  const auto k = static_cast<std::size_t>(i);
  snbrs_.clear();
  // The synchronous simulator: every neighbour's state is of this very step (age 0).
  for (std::size_t j = 0; j < x_.size(); ++j)
    if (j != k) snbrs_.push_back({static_cast<std::int32_t>(j), x_[j], 0.0, 0.0, brakes_.empty() ? Vec2::Zero() : brakes_[j]});
  const SafetyOutcome f = safety_filter(safety_, safety_state_[k], i, x_[k], r.x, snbrs_, zones_,
                                        brakes_.empty() ? Vec2::Zero() : brakes_[k]);
  counts_.interventions += f.intervened ? 1 : 0;
  counts_.sidesteps += f.sidestep_started ? 1 : 0;
  counts_.broken += f.broken;
  counts_.held += f.held ? 1 : 0;
  const bool blocked = f.held || f.sidestep;
  blocked_ += blocked ? 1 : 0;
  blocked_by_[k] = !blocked ? -1 : f.blocking_id >= 0 ? f.blocking_id : f.blocking_zone >= 0 ? -2 - f.blocking_zone : -1;
  if (vehicles_.empty()) return f.x;
  bool outside = false;
  const Vec2 x = drive_safely(vehicle_, vehicles_[k], r, f, cmd_.dt, cmd_.workspace, outside).x;
  counts_.outside += outside ? 1 : 0;
  return x;
}

void Swarm::step_batch() {
  paper_velocities_batch(cmd_, x_, t_, v_, batch_);
  for (std::size_t i = 0; i < x_.size(); ++i) {
    const Vec2 next = x_[i] + cmd_.dt * v_[i];
    bool clamped = false;  // as agent_step: a non-finite step is not taken, the workspace is kept
    const Vec2 law = next.allFinite() ? keep_inside(next, cmd_.workspace, clamped) : x_[i];
    x_[i] = move(static_cast<int>(i), {law, (law - x_[i]) / cmd_.dt, clamped});
  }
}

void Swarm::step() {
  const int n = static_cast<int>(x_.size());
  if (cmd_.hold)
    for (VehicleState& v : vehicles_) stop(v);  // held: nobody moves, and no vehicle coasts on
  if (kernel_ == Kernel::Batch && batch_applies(cmd_, vehicle_)) {
    step_batch();
    t_ += cmd_.dt;
    ++steps_;
    return;
  }
  if (cmd_.law == Law::Arc) {
    // Each agent publishes its own arc length; the others use it (as agent processes do).
    const ShapeSpec s = shape_at(cmd_, t_);
    for (int j = 0; j < n; ++j) arc_[j] = closest_point(s, cmd_.curve(), x_[j]).s;
  }
  // Held, nobody moves: the filter has nothing to keep.
  const bool safe = filters(cmd_) && !cmd_.hold;
  blocked_ = 0;
  // Double integrators: every braking segment as the step starts (the vehicles change as they move).
  brakes_.clear();
  if (safe && safety_.braking && !vehicles_.empty()) {
    const double h = cmd_.dt * vehicle_.seconds_per_model_time;
    for (const VehicleState& v : vehicles_) brakes_.push_back(braking_displacement(v.velocity, vehicle_.max_accel, h));
  }
  for (int i = 0; i < n; ++i) {
    nbrs_.clear();
    for (int j = 0; j < n; ++j)
      if (j != i) nbrs_.push_back({j, x_[j], cmd_.law == Law::Arc ? arc_[j] : std::numeric_limits<double>::quiet_NaN()});
    const StepResult r = agent_step(cmd_, i, x_[i], nbrs_, t_);
    next_[i] = safe ? move_safely(i, r) : move(i, r);
  }
  std::swap(x_, next_);
  t_ += cmd_.dt;
  ++steps_;
}

}  // namespace shapeform::core
