#pragma once
/// Basic types of the pure core. The core includes only Eigen and the standard library.
#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <vector>

namespace shapeform::core {

/// A point or vector in the plane, in shape units (the paper's x1, x2).
using Vec2 = Eigen::Vector2d;

/// Another agent as one agent sees it: its id and its last known position.
struct Neighbour {
  std::int32_t id = 0;
  Vec2 x = Vec2::Zero();
  /// The neighbour's arc length along the current shape, when it published one for the same command
  /// (NaN when unknown: the arc law then projects x itself).
  double s = std::numeric_limits<double>::quiet_NaN();
};

/// A keep-out zone (`safety.keep_out`): a region no agent may enter, in shape units, world frame.
struct KeepOutZone {
  enum class Kind { Circle, Polygon };
  Kind kind = Kind::Circle;
  Vec2 centre = Vec2::Zero();  ///< circle: its centre
  double radius = 0.0;         ///< circle: its radius, > 0
  /// polygon: a simple polygon's vertices in order (either orientation, >= 3, convex or not)
  std::vector<Vec2> vertices;

  bool operator==(const KeepOutZone& o) const {
    return kind == o.kind && centre == o.centre && radius == o.radius && vertices == o.vertices;
  }
  bool operator!=(const KeepOutZone& o) const { return !(*this == o); }
};

}  // namespace shapeform::core
