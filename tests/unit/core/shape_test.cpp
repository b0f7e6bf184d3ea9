#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "core/command.hpp"
#include "core/curve.hpp"
#include "core/shape.hpp"

using namespace shapeform::core;

namespace {
std::vector<Vec2> sample_points(int n, double w, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-w, w);
  std::vector<Vec2> pts;
  for (int i = 0; i < n; ++i) pts.emplace_back(u(rng), u(rng));
  // Points on axes and diagonals, where radial projections are easiest to get wrong.
  for (double v : {-3.0, -0.5, 0.5, 3.0}) {
    pts.emplace_back(v, 0.0);
    pts.emplace_back(0.0, v);
    pts.emplace_back(v, v);
    pts.emplace_back(v, -v);
  }
  return pts;
}

/// Residual of the shape's implicit equation at p (0 on the shape).
double on_shape_residual(const ShapeSpec& s, const Vec2& p) {
  const Vec2 y = p - s.centre;
  switch (s.kind) {
    case ShapeKind::Line: return y.y() - (s.m * y.x() + s.c);  // translated like every shape
    case ShapeKind::Circle: return y.norm() - s.r0;
    case ShapeKind::Ellipse: return std::pow(y.x() / s.a, 2) + std::pow(y.y() / s.b, 2) - 1.0;
    case ShapeKind::Square: return std::max(std::abs(y.x()), std::abs(y.y())) - s.a;
    default: break;
  }
  return 1e9;
}

std::vector<ShapeSpec> paper_shapes(Vec2 centre) {
  std::vector<ShapeSpec> v;
  ShapeSpec s;
  s.centre = centre;
  s.kind = ShapeKind::Line, s.m = -1, s.c = 5;
  v.push_back(s);
  s.kind = ShapeKind::Line, s.m = 2.5, s.c = -1;
  v.push_back(s);
  s.kind = ShapeKind::Circle, s.r0 = 4;
  v.push_back(s);
  s.kind = ShapeKind::Ellipse, s.a = 4, s.b = 2;
  v.push_back(s);
  s.kind = ShapeKind::Square, s.a = 5;
  v.push_back(s);
  return v;
}

/// x_T(x) on an analytic shape, its curve compiled for the one query.
Vec2 target(const ShapeSpec& s, const Vec2& x) { return target_point(s, *make_curve(s), x); }
}  // namespace

TEST_CASE("every projection lies on its shape and is idempotent", "[shape]") {
  for (Vec2 centre : {Vec2(0, 0), Vec2(1.5, -2.0)}) {
    for (const ShapeSpec& s : paper_shapes(centre)) {
      INFO("shape " << to_string(s.kind) << " centre " << centre.transpose());
      const auto curve = make_curve(s);
      for (const Vec2& p : sample_points(200, 12.0, 7)) {
        const Vec2 xp = p + centre;
        const Vec2 t = target_point(s, *curve, xp);
        REQUIRE(std::isfinite(t.x()));
        REQUIRE(std::isfinite(t.y()));
        CHECK(std::abs(on_shape_residual(s, t)) < 1e-9);
        CHECK((target_point(s, *curve, t) - t).norm() < 1e-9);
      }
    }
  }
}

TEST_CASE("line projection: residual orthogonal to the line, closest point", "[shape]") {
  ShapeSpec s;
  s.kind = ShapeKind::Line;
  s.m = -1;
  s.c = 5;
  const Vec2 dir = Vec2(1, s.m).normalized();
  const auto curve = make_curve(s);
  for (const Vec2& p : sample_points(100, 10.0, 3)) {
    const Vec2 t = target_point(s, *curve, p);
    CHECK(std::abs((p - t).dot(dir)) < 1e-9);
    // No other point of the line is closer.
    for (double d : {-0.1, 0.1}) CHECK((p - (t + d * dir)).norm() > (p - t).norm());
  }
  // The paper's printed "+mc" would send (0, 0) to (2.5, -7.5), off the line; "+c" gives (2.5, 2.5).
  CHECK((target(s, Vec2(0, 0)) - Vec2(2.5, 2.5)).norm() < 1e-12);
}

TEST_CASE("closed projections are radial about the centre", "[shape]") {
  for (const ShapeSpec& s : paper_shapes(Vec2(0.5, 0.25))) {
    const auto curve = make_curve(s);
    if (!curve->closed()) continue;
    for (const Vec2& p : sample_points(100, 10.0, 11)) {
      const Vec2 y = p - s.centre;
      if (y.norm() < 1e-9) continue;
      const Vec2 t = target_point(s, *curve, p) - s.centre;
      CHECK(std::abs(y.x() * t.y() - y.y() * t.x()) < 1e-9 * (1 + y.norm() * t.norm()));  // parallel
      CHECK(y.dot(t) > 0);                                                                     // same side
    }
  }
}

TEST_CASE("square projection matches the paper's four cases", "[shape]") {
  ShapeSpec s;
  s.kind = ShapeKind::Square;
  s.a = 5;
  // |x2| <= |x1|, x1 > 0: (a, a x2/x1); |x2| > |x1|, x2 > 0: (a x1/x2, a); and the mirrored cases.
  CHECK((target(s, Vec2(2, 1)) - Vec2(5, 2.5)).norm() < 1e-12);
  CHECK((target(s, Vec2(-2, 1)) - Vec2(-5, 2.5)).norm() < 1e-12);
  CHECK((target(s, Vec2(1, 2)) - Vec2(2.5, 5)).norm() < 1e-12);
  CHECK((target(s, Vec2(1, -2)) - Vec2(2.5, -5)).norm() < 1e-12);
  CHECK((target(s, Vec2(0, 3)) - Vec2(0, 5)).norm() < 1e-12);   // x1 = 0
  CHECK((target(s, Vec2(2, 2)) - Vec2(5, 5)).norm() < 1e-12);   // diagonal
  CHECK((target(s, Vec2(-1, -1)) - Vec2(-5, -5)).norm() < 1e-12);
}

TEST_CASE("ellipse uses theta = atan2(a x2, b x1)", "[shape]") {
  ShapeSpec s;
  s.kind = ShapeKind::Ellipse;
  s.a = 4;
  s.b = 2;
  const Vec2 p(1.0, 3.0);
  const double th = std::atan2(4.0 * 3.0, 2.0 * 1.0);
  CHECK((target(s, p) - Vec2(4 * std::cos(th), 2 * std::sin(th))).norm() < 1e-12);
}

TEST_CASE("singular points: an agent at a centre goes to direction (1, 0)", "[shape][singular]") {
  for (const ShapeSpec& s : paper_shapes(Vec2(-1, 2))) {
    const auto curve = make_curve(s);
    if (!curve->closed()) continue;
    const Vec2 t = target_point(s, *curve, s.centre);
    REQUIRE(std::isfinite(t.x()));
    REQUIRE(std::isfinite(t.y()));
    CHECK(std::abs(t.y() - s.centre.y()) < 1e-12);
    CHECK(t.x() > s.centre.x());
    CHECK(std::abs(on_shape_residual(s, t)) < 1e-12);
  }
  // Tiny offsets from the centre stay finite and on the shape.
  ShapeSpec c;
  c.kind = ShapeKind::Circle;
  for (double eps : {1e-300, 1e-160, 1e-20}) {
    const Vec2 t = target(c, Vec2(eps, eps));
    CHECK(std::isfinite(t.norm()));
    CHECK(std::abs(t.norm() - c.r0) < 1e-9);
  }
}

TEST_CASE("centre paths", "[shape][tracking]") {
  CentrePath line;
  line.kind = CentrePath::Kind::Line;
  line.point = Vec2(-10, -10);
  line.velocity = Vec2(0.1, 0.1);
  CHECK((centre_at(line, 100) - Vec2(0, 0)).norm() < 1e-12);
  CHECK((centre_velocity(line, 5) - Vec2(0.1, 0.1)).norm() < 1e-15);

  CentrePath circ;
  circ.kind = CentrePath::Kind::Circle;
  circ.radius = 6;
  circ.period = 200;
  CHECK((centre_at(circ, 0) - Vec2(6, 0)).norm() < 1e-12);
  CHECK((centre_at(circ, 50) - Vec2(0, 6)).norm() < 1e-12);
  CHECK((centre_at(circ, 200) - Vec2(6, 0)).norm() < 1e-9);
  // The velocity is the derivative of the position (central difference).
  for (double t : {0.0, 13.0, 77.5}) {
    const Vec2 fd = (centre_at(circ, t + 1e-5) - centre_at(circ, t - 1e-5)) / 2e-5;
    CHECK((centre_velocity(circ, t) - fd).norm() < 1e-7);
  }
  CHECK(centre_velocity(circ, 0).norm() == Approx(6 * 2 * M_PI / 200));

  Command cmd;
  cmd.shape.kind = ShapeKind::Circle;
  cmd.shape.r0 = 2;
  cmd.tracking.enabled = true;
  cmd.tracking.path = line;
  CHECK((shape_at(cmd, 100).centre - Vec2(0, 0)).norm() < 1e-12);
  cmd.tracking.enabled = false;
  CHECK((shape_at(cmd, 100).centre - cmd.shape.centre).norm() == 0);
}

TEST_CASE("a path advanced by t starts where the path is at t", "[shape][tracking][hold]") {
  CentrePath line;
  line.kind = CentrePath::Kind::Line;
  line.point = Vec2(-10, 4);
  line.velocity = Vec2(0.1, -0.2);
  CentrePath circ;
  circ.kind = CentrePath::Kind::Circle;
  circ.origin = Vec2(1, 2);
  circ.radius = 6;
  circ.period = 200;
  circ.phase = 0.5;
  CentrePath fixed;
  fixed.point = Vec2(3, 3);
  for (const CentrePath& p : {line, circ, fixed}) {
    for (const double t : {0.0, 37.0, 450.0}) {
      const CentrePath q = advanced(p, t);
      for (const double s : {0.0, 1.0, 123.0}) {
        CHECK((centre_at(q, s) - centre_at(p, t + s)).norm() < 1e-9);
        CHECK((centre_velocity(q, s) - centre_velocity(p, t + s)).norm() < 1e-9);
      }
    }
  }
  CHECK(std::abs(advanced(circ, 1e6).phase) < 2 * M_PI);  // kept in one turn
}

TEST_CASE("shape and path names round-trip", "[shape]") {
  for (ShapeKind k : {ShapeKind::Line, ShapeKind::Circle, ShapeKind::Ellipse, ShapeKind::Square}) {
    ShapeKind out{};
    REQUIRE(parse_shape_kind(to_string(k), out));
    CHECK(out == k);
  }
  ShapeKind dummy{};
  CHECK_FALSE(parse_shape_kind("triangle", dummy));
  CentrePath::Kind pk{};
  CHECK(parse_path_kind("circle", pk));
  CHECK(pk == CentrePath::Kind::Circle);
  CHECK_FALSE(parse_path_kind("spiral", pk));
}

TEST_CASE("make_curve builds analytic shapes and polygons; expression kinds need shapes::compile", "[shape]") {
  for (const ShapeSpec& s : paper_shapes(Vec2(0, 0))) {
    INFO(to_string(s.kind));
    CHECK(make_curve(s)->closed() == (s.kind != ShapeKind::Line));
  }
  ShapeSpec poly;
  poly.kind = ShapeKind::Polygon;
  poly.vertices = {Vec2(0, 0), Vec2(4, 0), Vec2(4, 3)};
  CHECK(make_curve(poly)->length() == Approx(12.0));
  poly.closed = false;
  CHECK_FALSE(make_curve(poly)->closed());
  CHECK(make_curve(poly)->length() == Approx(7.0));
  for (ShapeKind k : {ShapeKind::Polar, ShapeKind::Parametric, ShapeKind::Implicit}) {
    ShapeSpec e;
    e.kind = k;
    CHECK_THROWS_WITH(make_curve(e), Catch::Contains(std::string(to_string(k)) + ": expression shapes must be compiled"));
  }
}

TEST_CASE("shape size: the scaled radius, semi-axis or half side; the curve's size otherwise", "[shape]") {
  ShapeSpec s;
  s.scale = 2;
  s.kind = ShapeKind::Circle, s.r0 = 3;
  CHECK(shape_size(s, *make_curve(s)) == 6.0);
  s.kind = ShapeKind::Ellipse, s.a = 1, s.b = 4;
  CHECK(shape_size(s, *make_curve(s)) == 8.0);
  s.kind = ShapeKind::Square, s.a = 5;
  CHECK(shape_size(s, *make_curve(s)) == 10.0);
  s.kind = ShapeKind::Line;
  CHECK(shape_size(s, *make_curve(s)) == 1.0);
  s.kind = ShapeKind::Polygon, s.vertices = {Vec2(0, 5), Vec2(-3, -4), Vec2(3, -4)};
  CHECK(shape_size(s, *make_curve(s)) == Approx(std::sqrt(6.0 * 6.0 + 9.0 * 9.0)));  // twice the half diagonal of the box
}
