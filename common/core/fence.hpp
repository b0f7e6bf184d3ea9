#pragma once
/// The geofence (issue 27, item 3; `safety.fence`, `safety.fence_margin`, `safety.breach_action`): a
/// convex polygon the agents stay inside, or, when Command::fence is empty, the workspace box
/// [-workspace, workspace]^2. The safety filter (safety.hpp) keeps every step inside the fence shrunk
/// by Command::fence_margin (fence_half_planes); an agent found beyond the fence itself (beyond_fence >
/// 0: a vehicle pushed out, a pose from outside, a late joiner placed outside) is a breach, and takes
/// Command::breach_action (docs/SAFETY.md, "Geofence").
///
/// Convex only: the filter's cell is convex, and so is the fence's inside shrunk by a margin, so the
/// fence is a set of half-planes and the nearest point back inside is unique. A region the agents must
/// not enter inside a convex fence is a keep-out zone (`safety.keep_out`).
///
/// Pure: Eigen and the standard library only.
#include <string>
#include <vector>

#include "command.hpp"
#include "half_plane.hpp"
#include "types.hpp"

namespace shapeform::core {

/// The problems of a fence, each a sentence naming the fence ("fence edges 0 and 2 cross (the fence
/// must be simple)"); none when usable: empty (the workspace box), or >= 3 finite vertices, no two
/// consecutive equal, not all collinear, simple and convex ("a fence must be convex; cut the rest out
/// with safety.keep_out"), every vertex inside the workspace box [-workspace, workspace]^2.
std::vector<std::string> fence_problems(const std::vector<Vec2>& fence, double workspace);

/// The fence as a counter-clockwise polygon: Command::fence turned counter-clockwise, or the
/// workspace box's 4 corners when it is empty. Requires a usable fence (fence_problems).
std::vector<Vec2> fence_polygon(const Command& cmd);

/// How far x is outside the fence (the polygon, or the workspace box when Command::fence is empty),
/// shape units; 0 inside or on it. > 0 is a breach.
double beyond_fence(const Command& cmd, const Vec2& x);

/// Where an agent at x returns to: the nearest point at least Command::fence_margin inside the fence
/// (x itself when already that far inside). When the fence is thinner than 2 fence_margin (nothing is
/// that far inside), the nearest of its deepest points.
Vec2 fence_return_point(const Command& cmd, const Vec2& x);

/// The fence shrunk by Command::fence_margin as half-planes n . p <= b (|n| = 1, n pointing out): one
/// per polygon edge, or the workspace box's 4 sides. Their intersection may be empty when the fence is
/// thinner than 2 fence_margin (the filter then keeps each agent from going further out).
std::vector<HalfPlane> fence_half_planes(const Command& cmd);

}  // namespace shapeform::core
