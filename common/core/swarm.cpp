#include "swarm.hpp"

#include <limits>
#include <random>
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

void Swarm::step() {
  const int n = static_cast<int>(x_.size());
  if (kernel_ == Kernel::Batch && cmd_.law == Law::Paper && cmd_.integrator == Integrator::Euler) {
    paper_velocities_batch(cmd_, x_, t_, v_, batch_);
    for (int i = 0; i < n; ++i) {
      const Vec2 next = x_[i] + cmd_.dt * v_[i];
      bool clamped = false;  // as agent_step: a non-finite step is not taken, the workspace is kept
      if (next.allFinite()) x_[i] = keep_inside(next, cmd_.workspace, clamped);
    }
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
    next_[i] = agent_step(cmd_, i, x_[i], nbrs_, t_).x;
  }
  std::swap(x_, next_);
  t_ += cmd_.dt;
  ++steps_;
}

}  // namespace shapeform::core
