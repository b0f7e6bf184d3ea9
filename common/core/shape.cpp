#include "shape.hpp"

#include <algorithm>
#include <cmath>

namespace shapeform::core {

namespace {
constexpr double kTwoPi = 6.283185307179586476925286766559;
}  // namespace

std::shared_ptr<const Curve> make_curve(const ShapeSpec& s) {
  switch (s.kind) {
    case ShapeKind::Line: return make_line(s.m, s.c);
    case ShapeKind::Circle: return make_circle(s.r0);
    case ShapeKind::Ellipse: return make_ellipse(s.a, s.b);
    case ShapeKind::Square: return make_square(s.a);
    case ShapeKind::Polygon: return make_polygon(s.vertices, s.closed);
    case ShapeKind::Polar:
    case ShapeKind::Parametric:
    case ShapeKind::Implicit: break;
  }
  throw ShapeError(std::string(to_string(s.kind)) + ": expression shapes must be compiled (shapes::compile)");
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

double shape_size(const ShapeSpec& s, const Curve& curve) {
  switch (s.kind) {
    case ShapeKind::Line: return 1.0;
    case ShapeKind::Circle: return s.scale * s.r0;
    case ShapeKind::Ellipse: return s.scale * std::max(s.a, s.b);
    case ShapeKind::Square: return s.scale * s.a;
    default: return s.scale * curve.size();
  }
}

Vec2 target_point(const ShapeSpec& s, const Curve& curve, const Vec2& x) {
  return to_world(s, curve.target(to_local(s, x)));
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

CentrePath advanced(const CentrePath& p, double t) {
  CentrePath out = p;
  switch (p.kind) {
    case CentrePath::Kind::Fixed: break;
    case CentrePath::Kind::Line: out.point = centre_at(p, t); break;
    case CentrePath::Kind::Circle: out.phase = std::fmod(p.phase + kTwoPi * t / p.period, kTwoPi); break;
  }
  return out;
}

}  // namespace shapeform::core
