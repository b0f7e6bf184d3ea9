#pragma once
/// The arc law (docs/LAW.md): every agent takes an arc-length slot on the curve, evenly spaced and
/// kept in order, and moves toward the curve point a bounded step toward its slot.
#include <cstdint>
#include <vector>

#include "curve.hpp"
#include "shape.hpp"
#include "types.hpp"

namespace shapeform::core {

/// Parameters of the arc law.
struct ArcParams {
  double k_normal = 0.5;   ///< rate toward the curve point ahead (1/model time)
  double k_tangent = 1.0;  ///< fraction of the slot error taken per step along the curve
  double spacing = 1.0;    ///< gap between agents on an infinite line (shape units)
};

/// The arc law's velocity for agent self_id at x on shape s (placed at its current centre; curve is
/// the curve compiled from s). Neighbours' arc lengths are used when given (finite), else computed
/// from their positions.
Vec2 arc_velocity(const ShapeSpec& s, const Curve& curve, const ArcParams& p, std::int32_t self_id,
                  const Vec2& x, const std::vector<Neighbour>& nbrs);

}  // namespace shapeform::core
