// The arc law on its own: slots along the curve, the bounded step toward them, the normal rate.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>
#include <limits>

#include "core/law_arc.hpp"

using namespace shapeform::core;

namespace {
ShapeSpec circle(double r0) {
  ShapeSpec s;
  s.kind = ShapeKind::Circle;
  s.r0 = r0;
  return s;
}
Vec2 on_circle(double r0, double angle) { return r0 * Vec2(std::cos(angle), std::sin(angle)); }
}  // namespace

TEST_CASE("arc law alone: k_normal times the way to the closest point", "[law][arc]") {
  const ShapeSpec s = circle(4);
  const auto curve = make_curve(s);
  ArcParams p;
  CHECK((arc_velocity(s, *curve, p, 0, Vec2(6, 0), {}) - Vec2(-1, 0)).norm() < 1e-12);
  p.k_normal = 0.25;
  CHECK((arc_velocity(s, *curve, p, 0, Vec2(0, 2), {}) - Vec2(0, 0.5)).norm() < 1e-12);
}

TEST_CASE("arc law: agents in their slots stay still", "[law][arc]") {
  const ShapeSpec s = circle(4);
  const auto curve = make_curve(s);
  const double third = 2 * M_PI / 3;
  const Vec2 a = on_circle(4, 0.2), b = on_circle(4, 0.2 + third), c = on_circle(4, 0.2 + 2 * third);
  CHECK(arc_velocity(s, *curve, ArcParams{}, 0, a, {{1, b}, {2, c}}).norm() < 1e-9);
  CHECK(arc_velocity(s, *curve, ArcParams{}, 2, c, {{0, a}, {1, b}}).norm() < 1e-9);
}

TEST_CASE("arc law: a neighbour's published arc length is used in place of its projection", "[law][arc]") {
  const ShapeSpec s = circle(4);
  const auto curve = make_curve(s);
  // Near their slots (half a circle apart), so no step is capped.
  const Vec2 me = on_circle(4, 0.1), other = on_circle(4, 0.1 + M_PI + 0.2);
  const Vec2 projected = arc_velocity(s, *curve, ArcParams{}, 0, me, {{1, other}});
  const double exact = closest_point(s, *curve, other).s;
  CHECK(arc_velocity(s, *curve, ArcParams{}, 0, me, {{1, other, exact}}) == projected);
  // A different published arc length moves the slots: the law listens to it.
  CHECK((arc_velocity(s, *curve, ArcParams{}, 0, me, {{1, other, exact + 0.5}}) - projected).norm() > 1e-3);
}

TEST_CASE("arc law: the step along a closed curve is capped (half a slot, a quarter of the size)", "[law][arc]") {
  const ShapeSpec s = circle(4);
  const auto curve = make_curve(s);
  // Two agents bunched together: each is half a circle from its slot, the step is capped at 1.
  const Vec2 a = on_circle(4, 0.0), b = on_circle(4, 0.05);
  const Vec2 va = arc_velocity(s, *curve, ArcParams{}, 0, a, {{1, b}});
  const Vec2 vb = arc_velocity(s, *curve, ArcParams{}, 1, b, {{0, a}});
  CHECK(va.norm() <= 0.5 * 1.0 + 1e-12);
  CHECK(va.norm() > 0.4);  // a full capped step (chord of an arc of 1 on radius 4)
  CHECK(va.dot(vb) < 0);   // apart, in opposite directions
}

TEST_CASE("arc law on the infinite line: a row at the commanded spacing, centred on the swarm", "[law][arc]") {
  ShapeSpec s;
  s.kind = ShapeKind::Line;
  s.m = 0;
  s.c = 0;
  const auto curve = make_curve(s);
  ArcParams p;  // spacing 1, k_tangent 1, k_normal 0.5
  // Agents at 0 and 3: slots at 1 and 2 (offset (0 + 3 - 1) / 2 = 1), no cap on the line.
  CHECK((arc_velocity(s, *curve, p, 0, Vec2(0, 0), {{1, Vec2(3, 0)}}) - Vec2(0.5, 0)).norm() < 1e-12);
  CHECK((arc_velocity(s, *curve, p, 1, Vec2(3, 0), {{0, Vec2(0, 0)}}) - Vec2(-0.5, 0)).norm() < 1e-12);
  p.spacing = 3;
  CHECK(arc_velocity(s, *curve, p, 0, Vec2(0, 0), {{1, Vec2(3, 0)}}).norm() < 1e-12);
}

TEST_CASE("arc law on an open curve: from end to end", "[law][arc]") {
  ShapeSpec s;
  s.kind = ShapeKind::Polygon;
  s.vertices = {Vec2(0, 0), Vec2(6, 0)};
  s.closed = false;
  const auto curve = make_curve(s);
  // Three agents: slots at 0, 3 and 6. The middle one at 3 stays; the first moves toward 0.
  const std::vector<Neighbour> others = {{1, Vec2(3, 0)}, {2, Vec2(5, 0)}};
  CHECK(arc_velocity(s, *curve, ArcParams{}, 1, Vec2(3, 0), {{0, Vec2(1, 0)}, {2, Vec2(5, 0)}}).norm() < 1e-12);
  CHECK(arc_velocity(s, *curve, ArcParams{}, 0, Vec2(1, 0), others).x() < 0);
}

TEST_CASE("sort_by_arc sorts as std::sort does, call after call, whatever the order it remembers", "[core][arc]") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 10.0), jitter(-0.05, 0.05);
  std::vector<std::pair<double, std::int32_t>> swarm;
  for (std::int32_t id = 0; id < 300; ++id) swarm.emplace_back(u(rng), id);
  for (int call = 0; call < 200; ++call) {
    // The agents move a little (a few overtake), some leave, some join, and the list comes in a new
    // order; every 50th call a reshuffle, every 70th an id twice, once ids past the indexed range.
    for (auto& [s, id] : swarm) s += call % 50 == 49 ? u(rng) : jitter(rng);
    if (call % 7 == 0 && !swarm.empty()) swarm.erase(swarm.begin() + static_cast<std::ptrdiff_t>(rng() % swarm.size()));
    if (call % 5 == 0) swarm.emplace_back(u(rng), 300 + call);
    std::vector<std::pair<double, std::int32_t>> in = swarm;
    std::shuffle(in.begin(), in.end(), rng);
    if (call % 70 == 69) in.push_back(in.front());
    if (call == 100) in.emplace_back(1.0, 1 << 24);
    std::vector<std::pair<double, std::int32_t>> expected = in;
    std::sort(expected.begin(), expected.end());
    sort_by_arc(in);
    REQUIRE(in == expected);
  }
}
