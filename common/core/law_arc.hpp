#pragma once
/// The arc law (docs/LAW.md): every agent takes an arc-length slot on the curve, evenly spaced and
/// kept in order, and moves toward the curve point a bounded step toward its slot.
#include <cstdint>
#include <utility>
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

/// Sorts (arc length, id) pairs ascending, as std::sort does (the order is unique: ids are distinct),
/// in about one pass when the ids come in nearly the order of the previous call on this thread (the
/// agents keep their order along the shape from one step to the next): the order is remembered per
/// thread. Falls back to std::sort for a reshuffle, repeated ids or ids outside 0..2^20.
void sort_by_arc(std::vector<std::pair<double, std::int32_t>>& all);

/// The arc law's velocity for agent self_id at x on shape s (placed at its current centre; curve is
/// the curve compiled from s). Neighbours' arc lengths are used when given (finite), else computed
/// from their positions.
Vec2 arc_velocity(const ShapeSpec& s, const Curve& curve, const ArcParams& p, std::int32_t self_id,
                  const Vec2& x, const std::vector<Neighbour>& nbrs);

/// The arc law for several agents that see one swarm (the agents one process hosts): out[k] is
/// hosted[k]'s velocity when it hears every agent of `others` and every other agent of `hosted`.
/// Bit for bit arc_velocity(s, curve, p, hosted[k].id, hosted[k].x, nbrs_k), nbrs_k being `others`
/// plus the other hosted agents with their arc lengths unknown (NaN: projected, as each projects
/// itself); the hosted agents' own `s` is ignored. The arc list is sorted and the common offset
/// computed once for all: O((H + N) log(H + N)) for H hosted agents instead of O(H N log N).
/// Ids are distinct across both lists.
void arc_velocities(const ShapeSpec& s, const Curve& curve, const ArcParams& p, const std::vector<Neighbour>& hosted,
                    const std::vector<Neighbour>& others, std::vector<Vec2>& out);

}  // namespace shapeform::core
