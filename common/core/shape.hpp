#pragma once
/// Shapes and their target vectors x_T(x): the point of the shape an agent at x is attracted to.
#include <string>
#include <string_view>

#include "types.hpp"

namespace shapeform::core {

enum class ShapeKind { Line, Circle, Ellipse, Square };

/// Name used in config files, console commands and JSON ("line", "circle", "ellipse", "square").
std::string_view to_string(ShapeKind kind);
/// Parses a shape name; returns false when unknown.
bool parse_shape_kind(std::string_view name, ShapeKind& out);

/// A commanded shape. Plain data; which fields matter depends on kind.
struct ShapeSpec {
  ShapeKind kind = ShapeKind::Circle;
  double m = -1.0;  ///< line slope: x2 = m x1 + c
  double c = 5.0;   ///< line intercept
  double r0 = 4.0;  ///< circle radius (> 0)
  double a = 4.0;   ///< ellipse semi-axis along x1, or square half side (> 0)
  double b = 2.0;   ///< ellipse semi-axis along x2 (> 0)
  Vec2 centre = Vec2::Zero();  ///< centre of closed shapes (ignored by the line)
};

/// True for closed curves (circle, ellipse, square); false for the line.
bool is_closed(ShapeKind kind);

/// Characteristic size of the shape (radius, larger semi-axis, half side; 1 for the line).
double shape_size(const ShapeSpec& s);

/// Target vector x_T(x), as the paper defines it:
///  - line: orthogonal projection onto x2 = m x1 + c;
///  - circle: radial projection centre + r0 (x - centre)/|x - centre|;
///  - ellipse: radial projection (a cos th, b sin th), th = atan2(a y2, b y1), y = x - centre;
///  - square: radial projection a y / max(|y1|, |y2|).
/// At the centre of a closed shape (singular) the direction (1, 0) is used. Always finite.
Vec2 target_point(const ShapeSpec& s, const Vec2& x);

/// Where the centre of a tracked shape is at model time t.
struct CentrePath {
  enum class Kind { Fixed, Line, Circle };
  Kind kind = Kind::Fixed;
  Vec2 point = Vec2::Zero();     ///< Fixed: the centre; Line: the centre at t = 0
  Vec2 velocity = Vec2::Zero();  ///< Line: units per model time unit
  Vec2 origin = Vec2::Zero();    ///< Circle: the centre of the circular path
  double radius = 6.0;           ///< Circle: path radius
  double period = 200.0;         ///< Circle: model time units per revolution (> 0)
  double phase = 0.0;            ///< Circle: angle at t = 0, radians
};

std::string_view to_string(CentrePath::Kind kind);
bool parse_path_kind(std::string_view name, CentrePath::Kind& out);

/// C(t).
Vec2 centre_at(const CentrePath& p, double t);
/// dC/dt at t.
Vec2 centre_velocity(const CentrePath& p, double t);

}  // namespace shapeform::core
