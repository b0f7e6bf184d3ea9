// The batched kernel (core::paper_velocities_batch) against the per-agent law (core::agent_velocity), on
// every instruction set this CPU runs: the same nearest neighbours, and velocities equal to rounding.
#include "core/batch.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <sstream>

#include "core/law.hpp"
#include "core/law_paper.hpp"
#include "core/shape.hpp"

using namespace shapeform::core;

namespace {

/// Every agent's velocity through agent_velocity, as an agent process computes it.
std::vector<Vec2> reference(const CompiledCommand& cmd, const std::vector<Vec2>& x, double t) {
  std::vector<Vec2> v;
  for (std::size_t i = 0; i < x.size(); ++i) {
    std::vector<Neighbour> nbrs;
    for (std::size_t j = 0; j < x.size(); ++j)
      if (j != i) nbrs.push_back({static_cast<std::int32_t>(j), x[j]});
    v.push_back(agent_velocity(cmd, static_cast<std::int32_t>(i), x[i], nbrs, t));
  }
  return v;
}

/// Sum of the magnitudes of agent i's terms (cohesion pairs, attraction, repulsion, feed-forward): the
/// scale that rounding errors of a sum are relative to (a velocity whose terms cancel is small, its
/// rounding error is not).
double magnitude(const CompiledCommand& cmd, const std::vector<Vec2>& x, std::size_t i, double t) {
  const Gains& g = cmd.gains;
  double m = std::abs(g.r) +
             attraction_term(x[i], target_point(shape_at(cmd, t), cmd.curve(), x[i]), g).norm() +
             (cmd.tracking.enabled ? centre_velocity(cmd.tracking.path, t).norm() : 0.0);
  for (std::size_t j = 0; j < x.size(); ++j)
    if (j != i) {
      const Vec2 d = x[j] - x[i];
      m += std::abs(g.k1) * std::pow(g.sigma * g.sigma + d.squaredNorm(), -g.beta) * d.norm();
    }
  return m;
}

/// n agents uniform in [-w, w]^2, some of them on a grid (equal distances: nearest-neighbour ties)
/// and some coincident (the escape direction).
std::vector<Vec2> swarm(int n, std::uint64_t seed, double w) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-w, w);
  std::vector<Vec2> x;
  for (int i = 0; i < n; ++i) {
    if (i % 5 == 3)
      x.emplace_back(std::round(u(rng)), std::round(u(rng)));  // grid points
    else if (i % 11 == 7)
      x.push_back(x[static_cast<std::size_t>(i) / 2]);  // coincident with another
    else
      x.emplace_back(u(rng), u(rng));
  }
  return x;
}

std::string name(Simd s) { return std::string(to_string(s)); }

}  // namespace

TEST_CASE("the batched kernel equals the per-agent law on every instruction set", "[batch]") {
  const std::vector<Simd> isas = simd_available();
  REQUIRE(isas.front() == Simd::Generic);
  double worst = 0.0;
  for (int n : {1, 2, 3, 7, 8, 9, 15, 16, 17, 33, 100, 257}) {
    for (double beta : {0.0, 0.5, 1.0, 1.2, 1.5, 2.0, 3.7}) {
      CompiledCommand cmd;
      cmd.gains.beta = beta;
      cmd.gains.sigma = n % 3 == 0 ? 0.4 : 3.5;
      cmd.tracking.enabled = n % 2 == 1;  // also a moving centre with feed-forward
      cmd.tracking.feedforward = true;
      cmd.tracking.path.kind = CentrePath::Kind::Circle;
      cmd.max_speed = n == 17 ? 0.3 : 0.0;
      const auto x =
          swarm(n, static_cast<std::uint64_t>(n) * 31 + static_cast<std::uint64_t>(beta * 10), 6.0);
      const auto ref = reference(cmd, x, 7.0);
      for (Simd isa : isas) {
        std::vector<Vec2> v;
        paper_velocities_batch(cmd, x, 7.0, v, {isa, 1});
        REQUIRE(v.size() == x.size());
        for (std::size_t i = 0; i < x.size(); ++i) {
          const double err = (v[i] - ref[i]).norm() / magnitude(cmd, x, i, 7.0);
          worst = std::max(worst, err);
          INFO(name(isa) << " n=" << n << " beta=" << beta << " agent " << i << ": " << v[i].transpose()
                         << " against " << ref[i].transpose());
          CHECK(err <= 1e-13);
        }
      }
    }
  }
  WARN("largest difference, relative to the sum of the terms' magnitudes: " << worst);
}

TEST_CASE("the batched kernel picks the per-agent law's nearest neighbours, ties to the lowest id",
          "[batch]") {
  // Only the repulsion (k1 = k2 = 0): one nearest neighbour per agent, so the velocities are equal
  // bit for bit, or some agent took another neighbour.
  CompiledCommand cmd;
  cmd.gains.k1 = 0.0;
  cmd.gains.k2 = 0.0;
  for (int n : {2, 3, 9, 64, 131, 600}) {
    // Integer points: many equal distances. Every tenth agent coincides with another.
    std::mt19937_64 rng(static_cast<std::uint64_t>(n));
    std::uniform_int_distribution<int> u(-4, 4);
    std::vector<Vec2> x;
    for (int i = 0; i < n; ++i)
      x.push_back(i % 10 == 9 ? x[static_cast<std::size_t>(i) / 3] : Vec2(u(rng), u(rng)));
    const auto ref = reference(cmd, x, 0.0);
    for (Simd isa : simd_available())
      for (int threads : {1, 2, 3}) {
        std::vector<Vec2> v;
        paper_velocities_batch(cmd, x, 0.0, v, {isa, threads});
        for (std::size_t i = 0; i < x.size(); ++i) {
          INFO(name(isa) << " threads=" << threads << " n=" << n << " agent " << i);
          CHECK(v[i] == ref[i]);
        }
      }
  }
  // Agent 1 at the origin is equidistant from agents 0, 2 and 3: the repulsion points away from 0.
  std::vector<Vec2> v;
  paper_velocities_batch(cmd, {Vec2(1, 0), Vec2(0, 0), Vec2(0, 1), Vec2(-1, 0)}, 0.0, v);
  CHECK(v[1] == Vec2(-0.1, 0));
}

TEST_CASE("the batched kernel split over threads equals the per-agent law", "[batch]") {
  CompiledCommand cmd;
  const auto x = swarm(1001, 9, 20.0);
  const auto ref = reference(cmd, x, 0.0);
  for (int threads : {2, 3}) {
    std::vector<Vec2> v;
    paper_velocities_batch(cmd, x, 0.0, v, {simd_best(), threads});
    for (std::size_t i = 0; i < x.size(); ++i) {
      INFO("threads=" << threads << " agent " << i);
      CHECK((v[i] - ref[i]).norm() <= 1e-13 * magnitude(cmd, x, i, 0.0));
    }
  }
}

TEST_CASE("the batched kernel across the workspace and at the ends of the power's range", "[batch]") {
  struct Case {
    double sigma, beta, half_width;
  };
  // Agents spread over the largest workspace (u up to 8e10); weights far below 2^-1022 (flushed or
  // subnormal, against std::pow's); a sigma so small that sigma^2 is subnormal and a weight so large
  // that the vectorised power cannot hold it (both take the per-agent law).
  for (const Case c :
       {Case{3.5, 1.2, 1e5}, Case{3.5, 300.0, 50.0}, Case{1e-160, 1.2, 5.0}, Case{1e-3, 200.0, 5.0}}) {
    CompiledCommand cmd;
    cmd.gains.sigma = c.sigma;
    cmd.gains.beta = c.beta;
    cmd.workspace = 1e5;
    const auto x = swarm(45, 3, c.half_width);
    const auto ref = reference(cmd, x, 0.0);
    for (Simd isa : simd_available()) {
      std::vector<Vec2> v;
      paper_velocities_batch(cmd, x, 0.0, v, {isa, 1});
      for (std::size_t i = 0; i < x.size(); ++i) {
        INFO(name(isa) << " sigma=" << c.sigma << " beta=" << c.beta << " agent " << i);
        REQUIRE(v[i].allFinite() == ref[i].allFinite());
        if (ref[i].allFinite()) CHECK((v[i] - ref[i]).norm() <= 1e-13 * magnitude(cmd, x, i, 0.0));
      }
    }
  }
}
