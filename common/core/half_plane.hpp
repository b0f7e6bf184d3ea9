#pragma once
/// A half-plane of the plane: the safety filter's constraints (safety.hpp) and the geofence's sides
/// (fence.hpp). Pure: Eigen only.
#include "types.hpp"

namespace shapeform::core {

/// A half-plane n . p <= b (|n| = 1).
struct HalfPlane {
  Vec2 n = Vec2::UnitX();
  double b = 0.0;
  bool contains(const Vec2& p, double tol = 0.0) const { return n.dot(p) <= b + tol; }
};

}  // namespace shapeform::core
