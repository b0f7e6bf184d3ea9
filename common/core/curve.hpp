#pragma once
/// Curves in their own (local) frame: the paper's target vector, the true closest point with its arc
/// length, and points by arc length. Every shape of the project is a Curve; ShapeSpec places it in
/// the world (centre, rotation, scale). Pure: Eigen and the standard library only.
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "types.hpp"

namespace shapeform::core {

/// A shape that cannot be built (bad parameters, degenerate polygon, no real points...).
class ShapeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The closest point of a curve to a query point.
struct Projection {
  Vec2 point = Vec2::Zero();    ///< closest point on the curve
  double s = 0.0;               ///< its arc length from the curve's start
  Vec2 tangent = Vec2(1, 0);    ///< unit tangent there (direction of increasing s)
  double distance = 0.0;        ///< |query - point|
};

class Curve {
 public:
  virtual ~Curve() = default;
  /// The paper's target vector x_T(y) (radial projection for star-shaped closed curves, orthogonal
  /// for the line, closest point or Newton projection otherwise). Always finite.
  virtual Vec2 target(const Vec2& y) const = 0;
  /// The true closest point, with arc length and tangent.
  virtual Projection closest(const Vec2& y) const = 0;
  /// Total arc length (infinity for the line).
  virtual double length() const = 0;
  virtual bool closed() const = 0;
  /// Point at arc length s (wrapped on closed curves, clamped on open ones).
  virtual Vec2 at(double s) const = 0;
  /// Characteristic size (radius-like), used to scale tolerances.
  virtual double size() const = 0;
};

/// An arc-length parameterised polyline: the workhorse behind sampled curves.
class Polyline {
 public:
  /// pts: vertices in order; closed: the last vertex joins the first. Throws ShapeError when
  /// degenerate (fewer than 2 distinct points, zero length).
  Polyline(std::vector<Vec2> pts, bool closed);
  Projection closest(const Vec2& y) const;
  Vec2 at(double s) const;
  double length() const { return length_; }
  bool closed() const { return closed_; }
  const std::vector<Vec2>& points() const { return pts_; }
  /// Largest distance of a vertex from the origin.
  double radius() const { return radius_; }

 private:
  Projection on_segment(std::size_t k, const Vec2& y) const;
  std::vector<Vec2> pts_;
  std::vector<double> cum_;  ///< arc length at each vertex (size = segments + 1)
  bool closed_;
  double length_ = 0.0;
  double radius_ = 0.0;
  /// Bounding boxes of runs of about sqrt(segments) segments: the exact closest-point search visits
  /// boxes nearest first and stops at the first box farther than the best hit.
  struct Chunk {
    std::size_t first, last;  ///< segments [first, last)
    Vec2 lo, hi;
  };
  std::vector<Chunk> chunks_;
};

/// The line x2 = m x1 + c (world frame only: it ignores centre/rotation/scale of ShapeSpec? no: it
/// lives in the local frame like every curve). Arc length is measured from the foot of the origin.
std::shared_ptr<const Curve> make_line(double m, double c);
std::shared_ptr<const Curve> make_circle(double r0);
/// Radial target (theta = atan2(a y2, b y1)); exact closest point by a refined polyline.
std::shared_ptr<const Curve> make_ellipse(double a, double b);
/// Radial target a y / max(|y1|, |y2|); closest point on the square's boundary.
std::shared_ptr<const Curve> make_square(double a);
/// Closest-point target. Closed polygons need >= 3 vertices, open >= 2; no zero-length edges.
std::shared_ptr<const Curve> make_polygon(std::vector<Vec2> vertices, bool closed);
/// Polar curve r(phi) sampled at `samples` angles (phi_k = 2 pi k / samples, r > 0 everywhere);
/// radial target with r interpolated; closest point on the sampled polyline.
std::shared_ptr<const Curve> make_polar(std::vector<double> r_samples);
/// A sampled parametric curve (points at s = k / (n-1) for s in [0, 1]); closest-point target.
std::shared_ptr<const Curve> make_sampled(std::vector<Vec2> points, bool closed);
/// Most separate pieces of f = 0 in the tracing box make_implicit accepts (a circle has 1, a hyperbola
/// 2, the lemniscate 1): more is a pattern (e.g. sin(50 x) sin(50 y) = 0.5), refused with a ShapeError.
inline constexpr int kImplicitPiecesMax = 16;
/// Implicit curve f(x, y) = 0: target by Newton steps along the gradient (numerical), falling back to
/// the closest point of the traced contour where the gradient vanishes or Newton does not converge.
/// The contour is traced by marching squares over [-half_box, half_box]^2 at `grid` cells per side;
/// its longest component defines arc length. Throws ShapeError when f has no zero in the box or more
/// than kImplicitPiecesMax pieces.
std::shared_ptr<const Curve> make_implicit(std::function<double(double, double)> f, double half_box = 20.0,
                                           int grid = 400);

}  // namespace shapeform::core
