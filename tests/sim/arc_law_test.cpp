// The arc law's acceptance criteria at the plateau, for every shape and swarm size, in the simulator.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>

#include "shapes/shapes.hpp"
#include "simulation.hpp"

using namespace shapeform;
using core::Vec2;

namespace {
core::CompiledCommand arc_command(core::ShapeKind kind) {
  core::Command c;
  c.law = core::Law::Arc;
  auto& s = c.shape;
  s.kind = kind;
  switch (kind) {
    case core::ShapeKind::Circle: s.r0 = 4; break;
    case core::ShapeKind::Ellipse: s.a = 4, s.b = 2; break;
    case core::ShapeKind::Square: s.a = 5; break;
    case core::ShapeKind::Line: s.m = -1, s.c = 5; break;
    case core::ShapeKind::Polar: s.r_expr = "4 + cos(5*phi)"; break;
    case core::ShapeKind::Polygon: s.vertices = {Vec2(0, 5), Vec2(-5, 1), Vec2(-3, -4), Vec2(3, -4), Vec2(5, 1)}; break;
    case core::ShapeKind::Implicit: s.f_expr = "x^4 + y^4 - 256"; break;  // a squircle of half width 4
    case core::ShapeKind::Parametric: s.x_expr = "4*cos(2*pi*s)", s.y_expr = "3*sin(4*pi*s)"; break;
  }
  return shapes::compile(c);
}

struct Plateau {
  double curve_error = 0, arc_gap_cv = 0, gap_cv = 0, max_step = 0, extent = 0;
};

Plateau run(const core::CompiledCommand& cmd, int n, long steps, std::uint64_t seed = 1) {
  const auto r = sim::run_simulation(cmd, core::uniform_start(n, seed), steps);
  return {r.metrics.curve_error_mean.value(), r.metrics.arc_gap_cv.value_or(1e9), r.metrics.gap_cv.value_or(1e9),
          r.max_step, r.metrics.extent.value_or(0)};
}
}  // namespace

TEST_CASE("arc law: exact, evenly spaced, still, on every closed shape and size", "[sim][arc]") {
  for (auto kind : {core::ShapeKind::Circle, core::ShapeKind::Ellipse, core::ShapeKind::Square, core::ShapeKind::Polar,
                    core::ShapeKind::Polygon, core::ShapeKind::Implicit}) {
    const core::CompiledCommand cmd = arc_command(kind);
    const double size = core::shape_size(cmd.shape, cmd.curve());
    for (int n : {3, 12, 50, 200}) {
      INFO(core::to_string(kind) << " N=" << n);
      const Plateau p = run(cmd, n, 600);
      CHECK(p.curve_error <= 1e-3 * size);
      CHECK(p.arc_gap_cv <= 0.01);
      CHECK(p.max_step <= 1e-4 * size);
    }
  }
}

TEST_CASE("arc law on a line: a finite row at the commanded spacing", "[sim][arc]") {
  core::CompiledCommand cmd = arc_command(core::ShapeKind::Line);
  for (int n : {3, 12, 50, 200}) {
    INFO("N=" << n);
    const Plateau a = run(cmd, n, 600);
    CHECK(a.curve_error <= 1e-3);
    CHECK(a.arc_gap_cv <= 0.01);
    CHECK(a.extent == Approx((n - 1) * cmd.arc.spacing).epsilon(1e-6));
    CHECK(a.max_step <= 1e-4);
    // Never growing: the same row much later.
    const Plateau b = run(cmd, n, 1200);
    CHECK(b.extent == Approx(a.extent).epsilon(1e-9));
  }
  cmd.arc.spacing = 0.5;
  CHECK(run(cmd, 12, 600).extent == Approx(5.5).epsilon(1e-6));
}

TEST_CASE("arc law on an open curve: from end to end", "[sim][arc]") {
  core::CompiledCommand cmd = arc_command(core::ShapeKind::Polygon);
  cmd.shape.closed = false;
  cmd = shapes::compile(cmd);  // a new shape: a new curve
  const Plateau p = run(cmd, 12, 600);
  CHECK(p.arc_gap_cv <= 0.01);
  CHECK(p.curve_error <= 1e-3 * core::shape_size(cmd.shape, cmd.curve()));
}

TEST_CASE("arc law settles no slower than the paper's law (12 agents, circle)", "[sim][arc]") {
  core::CompiledCommand paper = arc_command(core::ShapeKind::Circle);
  paper.law = core::Law::Paper;
  const core::CompiledCommand arc = arc_command(core::ShapeKind::Circle);
  std::vector<int> ps, as;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const auto p = sim::run_simulation(paper, core::uniform_start(12, seed), 500);
    const auto a = sim::run_simulation(arc, core::uniform_start(12, seed), 500);
    REQUIRE(p.settle_step);
    REQUIRE(a.settle_step);
    ps.push_back(*p.settle_step);
    as.push_back(*a.settle_step);
  }
  std::sort(ps.begin(), ps.end());
  std::sort(as.begin(), as.end());
  CHECK(as[5] <= ps[5]);
}

TEST_CASE("arc law tracks a moving centre with feed-forward (ring error <= 0.05)", "[sim][arc][tracking]") {
  for (auto path : {core::CentrePath::Kind::Line, core::CentrePath::Kind::Circle}) {
    core::CompiledCommand cmd = arc_command(core::ShapeKind::Circle);
    cmd.shape.r0 = 2;
    cmd = shapes::compile(cmd);
    cmd.tracking.enabled = true;
    cmd.tracking.feedforward = true;
    cmd.tracking.path.kind = path;
    cmd.tracking.path.point = Vec2(-10, -10);
    cmd.tracking.path.velocity = Vec2(0.1, 0.1);
    cmd.tracking.path.radius = 6;
    cmd.tracking.path.period = 200;
    const auto r = sim::run_simulation(cmd, core::uniform_start(10, 3), 200);
    CHECK(*r.metrics.ring_error <= 0.05);
    CHECK(*r.metrics.centroid_error <= 0.05);
  }
}

TEST_CASE("max_speed limits every step of both laws", "[sim][arc]") {
  for (auto law : {core::Law::Paper, core::Law::Arc}) {
    core::CompiledCommand cmd = arc_command(core::ShapeKind::Circle);
    cmd.law = law;
    cmd.max_speed = 0.05;
    core::Swarm s(cmd, core::uniform_start(12, 4));
    for (int k = 0; k < 50; ++k) {
      const auto before = s.positions();
      s.step();
      for (std::size_t i = 0; i < before.size(); ++i) CHECK((s.positions()[i] - before[i]).norm() <= 0.05 + 1e-12);
    }
  }
}
