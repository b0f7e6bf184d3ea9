#pragma once
/// Plane geometry and the checks of simple polygons shared by the keep-out zones (safety.hpp) and the
/// geofence (fence.hpp).
/// Pure: Eigen and the standard library only.
#include <string>
#include <vector>

#include "types.hpp"

#include <algorithm>

namespace shapeform::core {

/// The z component of the cross product a x b.
inline double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

/// The point of segment [a, b] nearest p.
inline Vec2 segment_point(const Vec2& a, const Vec2& b, const Vec2& p) {
  const Vec2 e = b - a;
  const double l2 = e.squaredNorm();
  const double t = l2 > 0.0 ? std::clamp((p - a).dot(e) / l2, 0.0, 1.0) : 0.0;
  return a + t * e;
}

/// Twice the signed area of the polygon v (> 0: counter-clockwise).
double twice_area(const std::vector<Vec2>& v);

/// The problems of v as a simple polygon, each a sentence naming it by `noun` ("polygon edges 0 and 2
/// cross (the polygon must be simple)"); none when usable: >= 3 finite vertices, no two consecutive
/// equal, whose edges do not cross, not all collinear.
std::vector<std::string> simple_polygon_problems(const std::vector<Vec2>& v, const std::string& noun);

}  // namespace shapeform::core
