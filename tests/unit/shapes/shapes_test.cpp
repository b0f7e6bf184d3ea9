// Shapes from equations and points: projection properties and errors.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "core/metrics.hpp"
#include "shapes/shapes.hpp"

using namespace shapeform;
using core::Vec2;

namespace {
core::ShapeSpec polar(const std::string& r) {
  core::ShapeSpec s;
  s.kind = core::ShapeKind::Polar;
  s.r_expr = r;
  shapes::compile(s);
  return s;
}
core::ShapeSpec parametric(const std::string& x, const std::string& y, bool closed) {
  core::ShapeSpec s;
  s.kind = core::ShapeKind::Parametric;
  s.x_expr = x;
  s.y_expr = y;
  s.closed = closed;
  shapes::compile(s);
  return s;
}
core::ShapeSpec implicit(const std::string& f) {
  core::ShapeSpec s;
  s.kind = core::ShapeKind::Implicit;
  s.f_expr = f;
  shapes::compile(s);
  return s;
}
core::ShapeSpec polygon(std::vector<Vec2> v, bool closed) {
  core::ShapeSpec s;
  s.kind = core::ShapeKind::Polygon;
  s.vertices = std::move(v);
  s.closed = closed;
  shapes::compile(s);
  return s;
}
std::vector<Vec2> points(int n, double w, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-w, w);
  std::vector<Vec2> p;
  for (int i = 0; i < n; ++i) p.emplace_back(u(rng), u(rng));
  return p;
}
/// Brute-force distance from y to the shape, from a dense sample of points on it.
double brute_distance(const core::ShapeSpec& s, const Vec2& y) {
  const auto c = core::curve_of(s);
  const double len = c->length();
  double best = 1e300;
  for (int k = 0; k <= 20000; ++k) best = std::min(best, (core::to_world(s, c->at(len * k / 20000.0)) - y).norm());
  return best;
}
void check_projection_properties(const core::ShapeSpec& s, double size) {
  const auto curve = core::curve_of(s);
  for (const Vec2& y : points(60, 2.0 * size, 5)) {
    const core::Projection p = core::closest_point(s, *curve, y);
    // On the curve: its own closest point is itself.
    const core::Projection again = core::closest_point(s, *curve, p.point);
    CHECK(again.distance < 1e-9 * size);
    CHECK((again.point - p.point).norm() < 1e-9 * size);
    // Closest: no sampled point of the curve is nearer (up to the sampling step).
    CHECK(p.distance <= brute_distance(s, y) + 1e-6 * size);
    // The target vector lies on the curve and is idempotent.
    const Vec2 t = core::target_point(s, y);
    REQUIRE(std::isfinite(t.norm()));
    CHECK(core::closest_point(s, *curve, t).distance < 1e-5 * size);
    CHECK((core::target_point(s, t) - t).norm() < 1e-5 * size);
    // Arc length and point agree.
    CHECK((core::to_world(s, curve->at(p.s / s.scale)) - p.point).norm() < 1e-9 * size);
  }
}
}  // namespace

TEST_CASE("polar r(phi): radial target on r = r(phi), closest projection", "[shapes]") {
  const auto s = polar("4 + cos(5*phi)");
  for (const Vec2& y : points(100, 8.0, 1)) {
    const Vec2 t = core::target_point(s, y);
    const double phi = std::atan2(y.y(), y.x());
    CHECK(t.norm() == Approx(4 + std::cos(5 * phi)).epsilon(1e-5));
    CHECK(std::abs(y.x() * t.y() - y.y() * t.x()) < 1e-9 * (1 + y.norm() * t.norm()));  // radial
  }
  check_projection_properties(s, 5.0);
  // An agent exactly at the centre goes along (1, 0) to r(0) = 5.
  CHECK((core::target_point(s, Vec2(0, 0)) - Vec2(5, 0)).norm() < 1e-9);
}

TEST_CASE("parametric x(s), y(s): open and closed", "[shapes]") {
  const auto closed = parametric("3*cos(2*pi*s)", "2*sin(2*pi*s)", true);
  CHECK(core::curve_of(closed)->closed());
  check_projection_properties(closed, 3.0);
  const auto open = parametric("4*s - 2", "(4*s-2)^2", false);  // a parabola arc
  CHECK_FALSE(core::curve_of(open)->closed());
  check_projection_properties(open, 4.0);
  // Ends: a point beyond the end projects onto the end point.
  CHECK((core::closest_point(open, *core::curve_of(open), Vec2(-10, 4)).point - Vec2(-2, 4)).norm() < 1e-9);
}

TEST_CASE("implicit f(x, y) = 0: Newton target on the curve, traced contour", "[shapes]") {
  const auto s = implicit("x^2/16 + y^2/4 - 1");
  const auto c = core::curve_of(s);
  CHECK(c->closed());
  CHECK(c->length() == Approx(19.3769).epsilon(1e-3));  // the ellipse's perimeter
  for (const Vec2& y : points(100, 8.0, 2)) {
    const Vec2 t = core::target_point(s, y);
    CHECK(std::abs(t.x() * t.x() / 16 + t.y() * t.y() / 4 - 1) < 1e-9);
  }
  check_projection_properties(s, 4.0);
  // At the centre the gradient vanishes: the defined fallback is the traced contour's closest point.
  const Vec2 t0 = core::target_point(s, Vec2(0, 0));
  CHECK(std::abs(t0.x() * t0.x() / 16 + t0.y() * t0.y() / 4 - 1) < 1e-3);
}

TEST_CASE("polygon: closest point on edges, closed and open", "[shapes]") {
  const auto tri = polygon({Vec2(0, 4), Vec2(-4, -3), Vec2(5, -2)}, true);
  check_projection_properties(tri, 5.0);
  CHECK(core::curve_of(tri)->length() == Approx((Vec2(0, 4) - Vec2(-4, -3)).norm() + (Vec2(-4, -3) - Vec2(5, -2)).norm() +
                                                (Vec2(5, -2) - Vec2(0, 4)).norm()));
  const auto path = polygon({Vec2(0, 0), Vec2(4, 0), Vec2(4, 4)}, false);
  CHECK((core::target_point(path, Vec2(2, -3)) - Vec2(2, 0)).norm() < 1e-12);
  CHECK((core::target_point(path, Vec2(5, 5)) - Vec2(4, 4)).norm() < 1e-12);
}

TEST_CASE("every shape can be translated, rotated and scaled", "[shapes]") {
  auto s = polar("4 + cos(5*phi)");
  s.centre = Vec2(2, -1);
  s.rotation = 0.7;
  s.scale = 0.5;
  shapes::compile(s);
  check_projection_properties(s, 2.5);
  // The point of the star at phi = 0 (r = 5) lands at centre + 0.5 * 5 (cos 0.7, sin 0.7).
  const Vec2 tip = s.centre + 2.5 * Vec2(std::cos(0.7), std::sin(0.7));
  CHECK(core::closest_point(s, *s.curve, tip).distance < 1e-9);
  CHECK(core::shape_size(s) == Approx(2.5));
  core::ShapeSpec sq;
  sq.kind = core::ShapeKind::Square;
  sq.a = 1;
  sq.rotation = M_PI / 4;
  sq.scale = 2;
  shapes::compile(sq);
  // A square of half side 2 rotated by 45 degrees has a corner on the x axis at 2 sqrt 2.
  CHECK(core::closest_point(sq, *sq.curve, Vec2(2 * std::sqrt(2.0), 0)).distance < 1e-9);
  check_projection_properties(sq, 2.0);
}

TEST_CASE("bad shapes are refused with a message naming the problem", "[shapes][errors]") {
  const auto message = [](core::ShapeSpec s) {
    try {
      shapes::compile(s);
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
  core::Command cmd;
  cmd.shape = polygon({Vec2(-5, -5), Vec2(5, -5), Vec2(5, 5), Vec2(-5, 5)}, true);
  // Four agents at the middles of the edges: arc gaps all 10; Euclidean gaps all 5 sqrt 2.
  const std::vector<Vec2> x = {Vec2(0, -5), Vec2(5, 0), Vec2(0, 5), Vec2(-5, 0)};
  const auto m = core::compute_metrics(cmd, x, 0);
  CHECK(*m.curve_error_max < 1e-12);
  CHECK(*m.arc_gap_cv < 1e-12);
  CHECK(*m.gap_cv < 1e-12);
  const auto gaps = core::arc_gaps(cmd.shape, x);
  REQUIRE(gaps.size() == 4);
  for (double g : gaps) CHECK(g == Approx(10.0));
  // Move one agent 1 unit off the square: curve error 1 for it.
  auto y = x;
  y[1] = Vec2(6, 0);
  CHECK(*core::compute_metrics(cmd, y, 0).curve_error_max == Approx(1.0));
}
