#pragma once
/// Shapes as plain data (ShapeSpec: what travels in config and on the wire), and the geometry of a
/// shape placed in the world given the curve compiled from it (target vector x_T(x), closest point).
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "curve.hpp"
#include "types.hpp"

namespace shapeform::core {

enum class ShapeKind { Line, Circle, Ellipse, Square, Polar, Parametric, Implicit, Polygon };

/// Name used in config files, console commands and JSON ("line", "circle", "ellipse", "square",
/// "polar", "parametric", "implicit", "polygon").
std::string_view to_string(ShapeKind kind);
/// Parses a shape name; returns false when unknown.
bool parse_shape_kind(std::string_view name, ShapeKind& out);

/// A commanded shape. Plain data; which fields matter depends on kind.
struct ShapeSpec {
  ShapeKind kind = ShapeKind::Circle;
  double m = -1.0;  ///< line slope: x2 = m x1 + c
  double c = 5.0;   ///< line intercept
  double r0 = 4.0;  ///< circle radius
  double a = 4.0;   ///< ellipse semi-axis along x1, or square half side
  double b = 2.0;   ///< ellipse semi-axis along x2
  Vec2 centre = Vec2::Zero();  ///< where the shape's origin is placed (the centre of closed shapes)
  double rotation = 0.0;       ///< counter-clockwise rotation about the centre, radians
  double scale = 1.0;          ///< uniform scale about the centre
  std::string r_expr;          ///< polar: r(phi), phi in [0, 2 pi)
  std::string x_expr, y_expr;  ///< parametric: x(s), y(s), s in [0, 1]
  std::string f_expr;          ///< implicit: f(x, y) = 0
  std::vector<Vec2> vertices;  ///< polygon vertices (local frame)
  bool closed = true;          ///< parametric and polygon: closed or open curve
};

/// The curve of an analytic shape (line, circle, ellipse, square) or a polygon, in the shape's local
/// frame. Expression kinds are compiled by shapes::compile_curve() (common/shapes, muparser): for
/// them this throws ShapeError naming the kind. Throws ShapeError on bad parameters.
std::shared_ptr<const Curve> make_curve(const ShapeSpec& s);

/// World <-> shape-local coordinates (translation, rotation, scale).
Vec2 to_local(const ShapeSpec& s, const Vec2& x);
Vec2 to_world(const ShapeSpec& s, const Vec2& y);

/// In the functions below, `curve` is the curve compiled from s (its local frame): s places it in the
/// world. Whether a shape is closed is curve.closed() (implicit: when its traced contour closes).

/// The true closest point of the shape in world coordinates (arc length scaled, tangent rotated).
Projection closest_point(const ShapeSpec& s, const Curve& curve, const Vec2& x);

/// Characteristic size of the shape (radius, larger semi-axis, half side; 1 for the line), scaled.
double shape_size(const ShapeSpec& s, const Curve& curve);

/// Target vector x_T(x), as the paper defines it (y = x in the shape's local frame; Curve::target):
///  - line: orthogonal projection onto x2 = m x1 + c;
///  - circle: radial projection r0 y/|y|;
///  - ellipse: radial projection (a cos th, b sin th), th = atan2(a y2, b y1);
///  - square: radial projection a y / max(|y1|, |y2|);
///  - polar: radial projection r(phi) y/|y|;
///  - parametric, polygon: the closest point; implicit: Newton steps along grad f.
/// At the centre of a closed shape (singular) the direction (1, 0) is used. Always finite.
Vec2 target_point(const ShapeSpec& s, const Curve& curve, const Vec2& x);

/// Where the centre of a tracked shape is at model time t.
struct CentrePath {
  enum class Kind { Fixed, Line, Circle };
  Kind kind = Kind::Fixed;
  Vec2 point = Vec2::Zero();     ///< Fixed: the centre; Line: the centre at t = 0
  Vec2 velocity = Vec2::Zero();  ///< Line: units per model time unit
  Vec2 origin = Vec2::Zero();    ///< Circle: the centre of the circular path
  double radius = 6.0;           ///< Circle: path radius
  double period = 200.0;         ///< Circle: model time units per revolution
  double phase = 0.0;            ///< Circle: angle at t = 0, radians
};

std::string_view to_string(CentrePath::Kind kind);
bool parse_path_kind(std::string_view name, CentrePath::Kind& out);

/// C(t).
Vec2 centre_at(const CentrePath& p, double t);
/// dC/dt at t.
Vec2 centre_velocity(const CentrePath& p, double t);
/// The same path started at model time t: advanced(p, t) at s is p at t + s (a line's point moved
/// on, a circle's phase turned; a fixed point unchanged). A held swarm's path restarts where it was.
CentrePath advanced(const CentrePath& p, double t);

}  // namespace shapeform::core
