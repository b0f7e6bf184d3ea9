#include "shape.hpp"

#include <algorithm>
#include <cmath>

#include "params.hpp"

namespace shapeform::core {

namespace {
constexpr double kTwoPi = 6.283185307179586476925286766559;

/// Unit vector along y, or (1, 0) when y is the zero vector (an agent exactly at a centre).
Vec2 direction_or_x(const Vec2& y) {
  const double n = std::hypot(y.x(), y.y());  // no underflow of the square near the centre
  if (n > 0.0 && std::isfinite(n)) return y / n;
  return Vec2(1.0, 0.0);
}
}  // namespace

std::string_view to_string(ShapeKind kind) { return params::name_of(params::kShapeKindNames, kind); }

bool parse_shape_kind(std::string_view name, ShapeKind& out) {
  return params::parse_name(params::kShapeKindNames, name, out);
}

bool is_closed(const ShapeSpec& s) {
  switch (s.kind) {
    case ShapeKind::Line: return false;
    case ShapeKind::Circle:
    case ShapeKind::Ellipse:
    case ShapeKind::Square:
    case ShapeKind::Polar: return true;
    case ShapeKind::Parametric:
    case ShapeKind::Polygon: return s.closed;
    case ShapeKind::Implicit: return s.curve ? s.curve->closed() : true;
  }
  return true;
}

void ensure_curve(ShapeSpec& s) {
  if (s.curve) return;
  switch (s.kind) {
    case ShapeKind::Line: s.curve = make_line(s.m, s.c); return;
    case ShapeKind::Circle: s.curve = make_circle(s.r0); return;
    case ShapeKind::Ellipse: s.curve = make_ellipse(s.a, s.b); return;
    case ShapeKind::Square: s.curve = make_square(s.a); return;
    case ShapeKind::Polygon: s.curve = make_polygon(s.vertices, s.closed); return;
    case ShapeKind::Polar:
    case ShapeKind::Parametric:
    case ShapeKind::Implicit:
      throw ShapeError(std::string(to_string(s.kind)) + ": expression shapes must be compiled (shapes::compile)");
  }
}

std::shared_ptr<const Curve> curve_of(const ShapeSpec& s) {
  if (s.curve) return s.curve;
  ShapeSpec copy = s;
  ensure_curve(copy);
  return copy.curve;
}

Vec2 to_local(const ShapeSpec& s, const Vec2& x) {
  const Vec2 d = x - s.centre;
  if (s.rotation == 0.0 && s.scale == 1.0) return d;
  const double c = std::cos(s.rotation), sn = std::sin(s.rotation);
  return Vec2(c * d.x() + sn * d.y(), -sn * d.x() + c * d.y()) / s.scale;
}

Vec2 to_world(const ShapeSpec& s, const Vec2& y) {
  if (s.rotation == 0.0 && s.scale == 1.0) return s.centre + y;
  const double c = std::cos(s.rotation), sn = std::sin(s.rotation);
  return s.centre + s.scale * Vec2(c * y.x() - sn * y.y(), sn * y.x() + c * y.y());
}

Projection closest_point(const ShapeSpec& s, const Curve& curve, const Vec2& x) {
  Projection p = curve.closest(to_local(s, x));
  p.point = to_world(s, p.point);
  p.s *= s.scale;
  if (s.rotation != 0.0) {
    const double c = std::cos(s.rotation), sn = std::sin(s.rotation);
    p.tangent = Vec2(c * p.tangent.x() - sn * p.tangent.y(), sn * p.tangent.x() + c * p.tangent.y());
  }
  p.distance = (x - p.point).norm();
  return p;
}

double shape_size(const ShapeSpec& s) {
  switch (s.kind) {
    case ShapeKind::Line: return 1.0;
    case ShapeKind::Circle: return s.scale * s.r0;
    case ShapeKind::Ellipse: return s.scale * std::max(s.a, s.b);
    case ShapeKind::Square: return s.scale * s.a;
    default: return s.curve ? s.scale * s.curve->size() : s.scale;
  }
}

Vec2 target_point(const ShapeSpec& s, const Vec2& x) {
  const Vec2 y = to_local(s, x);
  if (s.curve) return to_world(s, s.curve->target(y));
  switch (s.kind) {
    case ShapeKind::Line: {
      // Orthogonal projection onto x2 = m x1 + c (the paper prints "+mc" where "+c" is right).
      const double t1 = (y.x() + s.m * y.y() - s.m * s.c) / (1.0 + s.m * s.m);
      return to_world(s, Vec2(t1, s.m * t1 + s.c));
    }
    case ShapeKind::Circle:
      return to_world(s, s.r0 * direction_or_x(y));
    case ShapeKind::Ellipse: {
      // atan2(0, 0) = 0 gives (a, 0) at the centre: the same (1, 0) convention as the circle.
      const double th = std::atan2(s.a * y.y(), s.b * y.x());
      return to_world(s, Vec2(s.a * std::cos(th), s.b * std::sin(th)));
    }
    case ShapeKind::Square: {
      const double m = std::max(std::abs(y.x()), std::abs(y.y()));
      if (!(m > 0.0) || !std::isfinite(m)) return to_world(s, Vec2(s.a, 0.0));
      return to_world(s, (s.a / m) * y);
    }
    default:
      return to_world(s, curve_of(s)->target(y));
  }
}

std::string_view to_string(CentrePath::Kind kind) { return params::name_of(params::kPathKindNames, kind); }

bool parse_path_kind(std::string_view name, CentrePath::Kind& out) {
  return params::parse_name(params::kPathKindNames, name, out);
}

Vec2 centre_at(const CentrePath& p, double t) {
  switch (p.kind) {
    case CentrePath::Kind::Fixed: return p.point;
    case CentrePath::Kind::Line: return p.point + t * p.velocity;
    case CentrePath::Kind::Circle: {
      const double ang = p.phase + kTwoPi * t / p.period;
      return p.origin + p.radius * Vec2(std::cos(ang), std::sin(ang));
    }
  }
  return p.point;
}

Vec2 centre_velocity(const CentrePath& p, double t) {
  switch (p.kind) {
    case CentrePath::Kind::Fixed: return Vec2::Zero();
    case CentrePath::Kind::Line: return p.velocity;
    case CentrePath::Kind::Circle: {
      const double w = kTwoPi / p.period;
      const double ang = p.phase + w * t;
      return p.radius * w * Vec2(-std::sin(ang), std::cos(ang));
    }
  }
  return Vec2::Zero();
}

}  // namespace shapeform::core
