#include "shape.hpp"

#include <algorithm>
#include <cmath>

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

std::string_view to_string(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::Line: return "line";
    case ShapeKind::Circle: return "circle";
    case ShapeKind::Ellipse: return "ellipse";
    case ShapeKind::Square: return "square";
  }
  return "?";
}

bool parse_shape_kind(std::string_view name, ShapeKind& out) {
  for (ShapeKind k : {ShapeKind::Line, ShapeKind::Circle, ShapeKind::Ellipse, ShapeKind::Square}) {
    if (name == to_string(k)) {
      out = k;
      return true;
    }
  }
  return false;
}

bool is_closed(ShapeKind kind) { return kind != ShapeKind::Line; }

double shape_size(const ShapeSpec& s) {
  switch (s.kind) {
    case ShapeKind::Line: return 1.0;
    case ShapeKind::Circle: return s.r0;
    case ShapeKind::Ellipse: return std::max(s.a, s.b);
    case ShapeKind::Square: return s.a;
  }
  return 1.0;
}

Vec2 target_point(const ShapeSpec& s, const Vec2& x) {
  switch (s.kind) {
    case ShapeKind::Line: {
      // Orthogonal projection onto x2 = m x1 + c (the paper prints "+mc" where "+c" is right).
      const double t1 = (x.x() + s.m * x.y() - s.m * s.c) / (1.0 + s.m * s.m);
      return Vec2(t1, s.m * t1 + s.c);
    }
    case ShapeKind::Circle:
      return s.centre + s.r0 * direction_or_x(x - s.centre);
    case ShapeKind::Ellipse: {
      const Vec2 y = x - s.centre;
      // atan2(0, 0) = 0 gives (a, 0) at the centre: the same (1, 0) convention as the circle.
      const double th = std::atan2(s.a * y.y(), s.b * y.x());
      return s.centre + Vec2(s.a * std::cos(th), s.b * std::sin(th));
    }
    case ShapeKind::Square: {
      const Vec2 y = x - s.centre;
      const double m = std::max(std::abs(y.x()), std::abs(y.y()));
      if (!(m > 0.0) || !std::isfinite(m)) return s.centre + Vec2(s.a, 0.0);
      return s.centre + (s.a / m) * y;
    }
  }
  return x;
}

std::string_view to_string(CentrePath::Kind kind) {
  switch (kind) {
    case CentrePath::Kind::Fixed: return "fixed";
    case CentrePath::Kind::Line: return "line";
    case CentrePath::Kind::Circle: return "circle";
  }
  return "?";
}

bool parse_path_kind(std::string_view name, CentrePath::Kind& out) {
  for (auto k : {CentrePath::Kind::Fixed, CentrePath::Kind::Line, CentrePath::Kind::Circle}) {
    if (name == to_string(k)) {
      out = k;
      return true;
    }
  }
  return false;
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
