// Shapes from equations and points: projection properties and errors.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "core/metrics.hpp"
#include "shapes/shapes.hpp"

using namespace shapeform;
using core::Vec2;

namespace {
/// A shape and the curve compiled from it (shapes::compile_curve).
struct Compiled {
  core::ShapeSpec spec;
  std::shared_ptr<const core::Curve> curve;
  Vec2 target(const Vec2& y) const { return core::target_point(spec, *curve, y); }
  core::Projection closest(const Vec2& y) const { return core::closest_point(spec, *curve, y); }
};
Compiled compiled(const core::ShapeSpec& s) { return {s, shapes::compile_curve(s)}; }

Compiled polar(const std::string& r) {
  core::ShapeSpec s;
  s.kind = core::ShapeKind::Polar;
  s.r_expr = r;
  return compiled(s);
}
Compiled parametric(const std::string& x, const std::string& y, bool closed) {
  core::ShapeSpec s;
  s.kind = core::ShapeKind::Parametric;
  s.x_expr = x;
  s.y_expr = y;
  s.closed = closed;
  return compiled(s);
}
Compiled implicit(const std::string& f) {
  core::ShapeSpec s;
  s.kind = core::ShapeKind::Implicit;
  s.f_expr = f;
  return compiled(s);
}
Compiled polygon(std::vector<Vec2> v, bool closed) {
  core::ShapeSpec s;
  s.kind = core::ShapeKind::Polygon;
  s.vertices = std::move(v);
  s.closed = closed;
  return compiled(s);
}
std::vector<Vec2> points(int n, double w, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-w, w);
  std::vector<Vec2> p;
  for (int i = 0; i < n; ++i) p.emplace_back(u(rng), u(rng));
  return p;
}
/// Brute-force distance from y to the shape, from a dense sample of points on it.
double brute_distance(const Compiled& s, const Vec2& y) {
  const auto& c = s.curve;
  const double len = c->length();
  double best = 1e300;
  for (int k = 0; k <= 20000; ++k) best = std::min(best, (core::to_world(s.spec, c->at(len * k / 20000.0)) - y).norm());
  return best;
}
void check_projection_properties(const Compiled& s, double size) {
  const auto& curve = s.curve;
  for (const Vec2& y : points(60, 2.0 * size, 5)) {
    const core::Projection p = s.closest(y);
    // On the curve: its own closest point is itself.
    const core::Projection again = s.closest(p.point);
    CHECK(again.distance < 1e-9 * size);
    CHECK((again.point - p.point).norm() < 1e-9 * size);
    // Closest: no sampled point of the curve is nearer (up to the sampling step).
    CHECK(p.distance <= brute_distance(s, y) + 1e-6 * size);
    // The target vector lies on the curve and is idempotent.
    const Vec2 t = s.target(y);
    REQUIRE(std::isfinite(t.norm()));
    CHECK(s.closest(t).distance < 1e-5 * size);
    CHECK((s.target(t) - t).norm() < 1e-5 * size);
    // Arc length and point agree.
    CHECK((core::to_world(s.spec, curve->at(p.s / s.spec.scale)) - p.point).norm() < 1e-9 * size);
  }
}
}  // namespace

TEST_CASE("polar r(phi): radial target on r = r(phi), closest projection", "[shapes]") {
  const auto s = polar("4 + cos(5*phi)");
  for (const Vec2& y : points(100, 8.0, 1)) {
    const Vec2 t = s.target(y);
    const double phi = std::atan2(y.y(), y.x());
    CHECK(t.norm() == Approx(4 + std::cos(5 * phi)).epsilon(1e-5));
    CHECK(std::abs(y.x() * t.y() - y.y() * t.x()) < 1e-9 * (1 + y.norm() * t.norm()));  // radial
  }
  check_projection_properties(s, 5.0);
  // An agent exactly at the centre goes along (1, 0) to r(0) = 5.
  CHECK((s.target(Vec2(0, 0)) - Vec2(5, 0)).norm() < 1e-9);
}

TEST_CASE("parametric x(s), y(s): open and closed", "[shapes]") {
  const auto closed = parametric("3*cos(2*pi*s)", "2*sin(2*pi*s)", true);
  CHECK(closed.curve->closed());
  check_projection_properties(closed, 3.0);
  const auto open = parametric("4*s - 2", "(4*s-2)^2", false);  // a parabola arc
  CHECK_FALSE(open.curve->closed());
  check_projection_properties(open, 4.0);
  // Ends: a point beyond the end projects onto the end point.
  CHECK((open.closest(Vec2(-10, 4)).point - Vec2(-2, 4)).norm() < 1e-9);
}

TEST_CASE("implicit f(x, y) = 0: Newton target on the curve, traced contour", "[shapes]") {
  const auto s = implicit("x^2/16 + y^2/4 - 1");
  const auto& c = s.curve;
  CHECK(c->closed());
  CHECK(c->length() == Approx(19.3769).epsilon(1e-3));  // the ellipse's perimeter
  for (const Vec2& y : points(100, 8.0, 2)) {
    const Vec2 t = s.target(y);
    CHECK(std::abs(t.x() * t.x() / 16 + t.y() * t.y() / 4 - 1) < 1e-9);
  }
  check_projection_properties(s, 4.0);
  // At the centre the gradient vanishes: the defined fallback is the traced contour's closest point.
  const Vec2 t0 = s.target(Vec2(0, 0));
  CHECK(std::abs(t0.x() * t0.x() / 16 + t0.y() * t0.y() / 4 - 1) < 1e-3);
}

TEST_CASE("polygon: closest point on edges, closed and open", "[shapes]") {
  const auto tri = polygon({Vec2(0, 4), Vec2(-4, -3), Vec2(5, -2)}, true);
  check_projection_properties(tri, 5.0);
  CHECK(tri.curve->length() == Approx((Vec2(0, 4) - Vec2(-4, -3)).norm() + (Vec2(-4, -3) - Vec2(5, -2)).norm() +
                                                (Vec2(5, -2) - Vec2(0, 4)).norm()));
  const auto path = polygon({Vec2(0, 0), Vec2(4, 0), Vec2(4, 4)}, false);
  CHECK((path.target(Vec2(2, -3)) - Vec2(2, 0)).norm() < 1e-12);
  CHECK((path.target(Vec2(5, 5)) - Vec2(4, 4)).norm() < 1e-12);
}

TEST_CASE("every shape can be translated, rotated and scaled", "[shapes]") {
  core::ShapeSpec star = polar("4 + cos(5*phi)").spec;
  star.centre = Vec2(2, -1);
  star.rotation = 0.7;
  star.scale = 0.5;
  const Compiled s = compiled(star);
  check_projection_properties(s, 2.5);
  // The point of the star at phi = 0 (r = 5) lands at centre + 0.5 * 5 (cos 0.7, sin 0.7).
  const Vec2 tip = star.centre + 2.5 * Vec2(std::cos(0.7), std::sin(0.7));
  CHECK(s.closest(tip).distance < 1e-9);
  CHECK(core::shape_size(s.spec, *s.curve) == Approx(2.5));
  core::ShapeSpec square;
  square.kind = core::ShapeKind::Square;
  square.a = 1;
  square.rotation = M_PI / 4;
  square.scale = 2;
  const Compiled sq = compiled(square);
  // A square of half side 2 rotated by 45 degrees has a corner on the x axis at 2 sqrt 2.
  CHECK(sq.closest(Vec2(2 * std::sqrt(2.0), 0)).distance < 1e-9);
  check_projection_properties(sq, 2.0);
}

TEST_CASE("bad shapes are refused with a message naming the problem", "[shapes][errors]") {
  const auto message = [](const core::ShapeSpec& s) {
    try {
      shapes::compile_curve(s);
    } catch (const core::ShapeError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  core::ShapeSpec s;
  s.kind = core::ShapeKind::Polar;
  s.r_expr = "4 + cos(5*phi";
  CHECK_THAT(message(s), Catch::Contains("polar: r(phi) = '4 + cos(5*phi'"));
  s.r_expr = "4 + foo*phi";
  CHECK_THAT(message(s), Catch::Contains("foo"));
  s.r_expr = "cos(phi)";
  CHECK_THAT(message(s), Catch::Contains("must be finite and > 0"));
  s.r_expr = "";
  CHECK_THAT(message(s), Catch::Contains("empty expression"));
  s.kind = core::ShapeKind::Implicit;
  s.f_expr = "x^2 + y^2 + 1";
  CHECK_THAT(message(s), Catch::Contains("no real points"));
  s.f_expr = "x^2 + z^2 - 1";
  CHECK_THAT(message(s), Catch::Contains("z"));
  s.kind = core::ShapeKind::Parametric;
  s.x_expr = "s";
  s.y_expr = "1/(s-0.5)";
  CHECK_THAT(message(s), Catch::Contains("not finite"));
  s.kind = core::ShapeKind::Polygon;
  s.vertices = {Vec2(0, 0), Vec2(1, 1)};
  s.closed = true;
  CHECK_THAT(message(s), Catch::Contains("at least 3 vertices"));
  s.vertices = {Vec2(0, 0), Vec2(1, 1), Vec2(1, 1)};
  CHECK_THAT(message(s), Catch::Contains("coincide"));
  s.vertices = {Vec2(0, 0), Vec2(1, 1), Vec2(2, 2)};
  CHECK_THAT(message(s), Catch::Contains("collinear"));
  s.kind = core::ShapeKind::Circle;
  s.scale = 0;
  CHECK_THAT(message(s), Catch::Contains("scale"));
}

TEST_CASE("metrics for any curve: closest-point error and arc-length gaps", "[shapes][metrics]") {
  core::Command square;
  square.shape = polygon({Vec2(-5, -5), Vec2(5, -5), Vec2(5, 5), Vec2(-5, 5)}, true).spec;
  const core::CompiledCommand cmd = shapes::compile(square);
  // Four agents at the middles of the edges: arc gaps all 10; Euclidean gaps all 5 sqrt 2.
  const std::vector<Vec2> x = {Vec2(0, -5), Vec2(5, 0), Vec2(0, 5), Vec2(-5, 0)};
  const auto m = core::compute_metrics(cmd, x, 0);
  CHECK(*m.curve_error_max < 1e-12);
  CHECK(*m.arc_gap_cv < 1e-12);
  CHECK(*m.gap_cv < 1e-12);
  const auto gaps = core::arc_gaps(cmd.shape, cmd.curve(), x);
  REQUIRE(gaps.size() == 4);
  for (double g : gaps) CHECK(g == Approx(10.0));
  // Move one agent 1 unit off the square: curve error 1 for it.
  auto y = x;
  y[1] = Vec2(6, 0);
  CHECK(*core::compute_metrics(cmd, y, 0).curve_error_max == Approx(1.0));
}

TEST_CASE("compile: a command with the curve of its shape, every kind", "[shapes]") {
  core::Command cmd;
  cmd.shape.kind = core::ShapeKind::Polar;
  cmd.shape.r_expr = "3";
  cmd.gains.k1 = 0.5;
  const core::CompiledCommand c = shapes::compile(cmd);
  CHECK(c.gains.k1 == 0.5);
  CHECK(c.curve().length() == Approx(2 * M_PI * 3).epsilon(1e-5));
  cmd.shape.kind = core::ShapeKind::Ellipse;  // analytic kinds: core::make_curve
  CHECK(shapes::compile(cmd).curve().length() == Approx(core::make_curve(cmd.shape)->length()));
  cmd.shape.scale = -1;  // placement is checked for every kind
  CHECK_THROWS_WITH(shapes::compile(cmd), Catch::Contains("scale"));
}
