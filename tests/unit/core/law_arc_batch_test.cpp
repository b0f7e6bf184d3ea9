// The arc law shared by the agents of one process (core::arc_velocities, core::agent_steps) against
// each agent on its own (core::arc_velocity, core::agent_step): the same bits, on closed, open and
// infinite curves, with ties, for 1 to 1000 agents.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "core/law.hpp"
#include "core/law_arc.hpp"

using namespace shapeform::core;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

ShapeSpec shape_of(ShapeKind kind) {
  ShapeSpec s;
  s.kind = kind;
  s.r0 = 4;
  if (kind == ShapeKind::Polygon) {
    s.vertices = {Vec2(-5, -1), Vec2(0, 2), Vec2(5, -1)};
    s.closed = false;  // an open curve: slots from end to end
  }
  return s;
}

/// n agents of a swarm (ids shuffled, not in order) around the shape; `ties` puts several agents on
/// one point, so their arc lengths tie and only their ids order them. The first `hosted` are the
/// process's own; the others carry published arc lengths (some unknown: NaN, projected).
struct Swarm {
  std::vector<Neighbour> hosted, others;
};
Swarm make_swarm(const ShapeSpec& s, const Curve& curve, int n, int hosted, bool ties, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-6, 6);
  std::vector<std::int32_t> ids(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) ids[static_cast<std::size_t>(i)] = 3 * i + 7;
  std::shuffle(ids.begin(), ids.end(), rng);
  Swarm w;
  for (int i = 0; i < n; ++i) {
    Neighbour a{ids[static_cast<std::size_t>(i)], Vec2(u(rng), u(rng))};
    if (ties && i % 3 == 1) a.x = (i < hosted ? w.hosted : w.others).empty() ? a.x
                                 : (i < hosted ? w.hosted : w.others).back().x;
    if (i < hosted) {
      w.hosted.push_back(a);
    } else {
      // Most published their arc length (exactly the projection: the law then agrees with itself),
      // some did not (another command: projected by the receiver), some publish one of their own.
      const double proj = closest_point(s, curve, a.x).s;
      a.s = i % 5 == 0 ? kNaN : (i % 7 == 0 ? proj + 0.25 : proj);
      w.others.push_back(a);
    }
  }
  return w;
}

/// Agent k's neighbours as a table of its own would give them: the others, then the other hosted
/// agents (their arc lengths unknown: each projects itself, so do they).
std::vector<Neighbour> neighbours_of(const Swarm& w, std::size_t k) {
  std::vector<Neighbour> nbrs = w.others;
  for (std::size_t j = 0; j < w.hosted.size(); ++j)
    if (j != k) nbrs.push_back({w.hosted[j].id, w.hosted[j].x});
  return nbrs;
}

}  // namespace

TEST_CASE("shared arc law: bit for bit each agent's own, closed, open and infinite, with ties", "[law][arc]") {
  for (const ShapeKind kind : {ShapeKind::Circle, ShapeKind::Ellipse, ShapeKind::Polygon, ShapeKind::Line}) {
    const ShapeSpec s = shape_of(kind);
    const auto curve = make_curve(s);
    ArcParams p;
    p.k_tangent = 0.7;
    for (const auto& [n, hosted] : std::vector<std::pair<int, int>>{{1, 1}, {2, 1}, {2, 2}, {3, 2}, {12, 5},
                                                                     {100, 50}, {1000, 100}, {1000, 1}}) {
      for (const bool ties : {false, true}) {
        INFO(std::string(to_string(kind)) << ", N = " << n << ", hosted " << hosted << (ties ? ", ties" : ""));
        const Swarm w = make_swarm(s, *curve, n, hosted, ties, static_cast<unsigned>(n * 31 + hosted));
        std::vector<Vec2> shared;
        arc_velocities(s, *curve, p, w.hosted, w.others, shared);
        REQUIRE(shared.size() == w.hosted.size());
        for (std::size_t k = 0; k < w.hosted.size(); ++k) {
          const Vec2 own = arc_velocity(s, *curve, p, w.hosted[k].id, w.hosted[k].x, neighbours_of(w, k));
          // Exact equality: the same sorted list and offset, the same operations in the same order.
          CHECK(shared[k].x() == own.x());
          CHECK(shared[k].y() == own.y());
        }
      }
    }
  }
}

TEST_CASE("shared steps: agent_steps equals agent_step per agent (Euler shared, RK4 and paper each alone)",
          "[law][arc]") {
  Command c;
  c.shape.kind = ShapeKind::Ellipse;
  c.shape.centre = Vec2(0.5, -1);
  c.tracking.enabled = true;
  c.tracking.feedforward = true;
  c.tracking.path.kind = CentrePath::Kind::Line;
  c.tracking.path.velocity = Vec2(0.2, 0.1);
  c.max_speed = 0.8;  // some agents are limited
  for (const Law law : {Law::Arc, Law::Paper}) {
    for (const Integrator integ : {Integrator::Euler, Integrator::RK4}) {
      c.law = law;
      c.integrator = integ;
      const CompiledCommand cmd = compile(c);
      CHECK(shares_steps(cmd) == (law == Law::Arc && integ == Integrator::Euler));
      const Swarm w = make_swarm(cmd.shape, cmd.curve(), 60, 20, true, 5);
      std::vector<StepResult> shared;
      agent_steps(cmd, w.hosted, w.others, 3.0, shared);
      REQUIRE(shared.size() == w.hosted.size());
      for (std::size_t k = 0; k < w.hosted.size(); ++k) {
        const StepResult own = agent_step(cmd, w.hosted[k].id, w.hosted[k].x, neighbours_of(w, k), 3.0);
        CHECK(shared[k].x.x() == own.x.x());
        CHECK(shared[k].x.y() == own.x.y());
        CHECK(shared[k].v.x() == own.v.x());
        CHECK(shared[k].v.y() == own.v.y());
        CHECK(shared[k].clamped == own.clamped);
      }
    }
  }
}
