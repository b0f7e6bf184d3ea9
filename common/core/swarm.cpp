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
    : cmd_(std::move(cmd)), x_(std::move(start)), next_(x_.size()), arc_(x_.size()) {
  nbrs_.reserve(x_.size());
}

bool batch_applies(const CompiledCommand& cmd, const VehicleParams& vehicle) {
  return cmd.law == Law::Paper && cmd.integrator == Integrator::Euler && vehicle.model == VehicleModel::Integrator;
}

void Swarm::set_vehicle(const VehicleParams& p, const std::vector<double>& headings) {
  if (!headings.empty() && headings.size() != x_.size())
    throw std::invalid_argument("Swarm::set_vehicle: " + std::to_string(headings.size()) + " headings for " +
                                std::to_string(x_.size()) + " agents");
  vehicle_ = p;
  vehicles_.clear();
  if (moves_as_law(p)) return;
  for (std::size_t i = 0; i < x_.size(); ++i)
    vehicles_.push_back(vehicle_start(x_[i], headings.empty() ? p.initial_heading : headings[i]));
}

Vec2 Swarm::move(int i, const StepResult& r) {
  if (vehicles_.empty()) return r.x;
  return drive(vehicle_, vehicles_[static_cast<std::size_t>(i)], r, cmd_.dt, cmd_.workspace).x;
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
  for (int i = 0; i < n; ++i) {
    nbrs_.clear();
    for (int j = 0; j < n; ++j)
      if (j != i) nbrs_.push_back({j, x_[j], cmd_.law == Law::Arc ? arc_[j] : std::numeric_limits<double>::quiet_NaN()});
    next_[i] = move(i, agent_step(cmd_, i, x_[i], nbrs_, t_));
  }
  std::swap(x_, next_);
  t_ += cmd_.dt;
  ++steps_;
}

}  // namespace shapeform::core
