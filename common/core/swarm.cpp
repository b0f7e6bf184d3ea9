#include "swarm.hpp"

#include <cmath>
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

void paper_velocities_batch(const CompiledCommand& cmd, const std::vector<Vec2>& x, double t, std::vector<Vec2>& v) {
  const auto n = static_cast<Eigen::Index>(x.size());
  const Gains& g = cmd.gains;
  const ShapeSpec s = shape_at(cmd, t);
  // Structure of arrays and row buffers, reused between calls: O(N) memory, no allocation per row.
  thread_local Eigen::ArrayXd X, Y, VX, VY, NN, NI, D2, W;
  X.resize(n), Y.resize(n), D2.resize(n), W.resize(n);
  VX.setZero(n), VY.setZero(n);
  NN.setConstant(n, std::numeric_limits<double>::infinity());
  NI.setConstant(n, -1.0);  // neighbour index as a double, so the selects below vectorise
  for (Eigen::Index i = 0; i < n; ++i) X[i] = x[i].x(), Y[i] = x[i].y();
  const double s2 = g.sigma * g.sigma;
  const auto k1 = static_cast<float>(g.k1), mbeta = static_cast<float>(-g.beta);
  for (Eigen::Index i = 0; i + 1 < n; ++i) {
    const Eigen::Index m = n - i - 1;  // pairs (i, j) for j > i, each computed once
    const auto dx = X.segment(i + 1, m) - X[i];
    const auto dy = Y.segment(i + 1, m) - Y[i];
    auto d2 = D2.head(m);
    auto w = W.head(m);
    d2 = dx * dx + dy * dy;
    // k1 (sigma^2 + d^2)^-beta in single precision (relative error ~1e-7; sums stay in double):
    // the log and exp dominate the cost, and float packets hold twice the lanes.
    w = (k1 * (mbeta * (s2 + d2).cast<float>().log()).exp()).cast<double>();
    VX[i] += (w * dx).sum();
    VY[i] += (w * dy).sum();
    VX.segment(i + 1, m) -= w * dx;
    VY.segment(i + 1, m) -= w * dy;
    // Nearest neighbours. Candidates reach every agent in ascending id and only a strictly nearer
    // one replaces the current, so ties go to the lowest id (as nearest_neighbour does).
    const double dmin = d2.minCoeff();
    if (dmin < NN[i]) {
      Eigen::Index k = 0;
      while (d2[k] != dmin) ++k;  // the first minimum: lowest id among ties
      NN[i] = dmin;
      NI[i] = static_cast<double>(i + 1 + k);
    }
    const auto nearer = d2 < NN.segment(i + 1, m);
    NI.segment(i + 1, m) = nearer.select(static_cast<double>(i), NI.segment(i + 1, m));
    NN.segment(i + 1, m) = nearer.select(d2, NN.segment(i + 1, m));
  }
  v.resize(x.size());
  const bool ff = cmd.tracking.enabled && cmd.tracking.feedforward;
  const Vec2 cv = ff ? centre_velocity(cmd.tracking.path, t) : Vec2::Zero();
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vec2& xi = x[static_cast<std::size_t>(i)];
    Vec2 vi = Vec2(VX[i], VY[i]) + attraction_term(xi, target_point(s, cmd.curve(), xi), g);
    if (NI[i] >= 0 && g.r != 0.0) {
      const Vec2 d = xi - x[static_cast<std::size_t>(NI[i])];
      const double len = std::hypot(d.x(), d.y());
      vi += (len > 0.0 && std::isfinite(len)) ? Vec2((g.r / len) * d) : Vec2(g.r * escape_direction(static_cast<std::int32_t>(i)));
    }
    vi += cv;
    if (cmd.max_speed > 0.0 && vi.norm() > cmd.max_speed) vi *= cmd.max_speed / vi.norm();
    v[static_cast<std::size_t>(i)] = vi;
  }
}

void Swarm::step() {
  const int n = static_cast<int>(x_.size());
  if (kernel_ == Kernel::Batch && cmd_.law == Law::Paper && cmd_.integrator == Integrator::Euler) {
    paper_velocities_batch(cmd_, x_, t_, v_);
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
