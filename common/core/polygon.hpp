#pragma once
/// Checks of simple polygons shared by the keep-out zones (safety.hpp) and the geofence (fence.hpp).
/// Pure: Eigen and the standard library only.
#include <string>
#include <vector>

#include "types.hpp"

namespace shapeform::core {

/// Twice the signed area of the polygon v (> 0: counter-clockwise).
double twice_area(const std::vector<Vec2>& v);

/// The problems of v as a simple polygon, each a sentence naming it by `noun` ("polygon edges 0 and 2
/// cross (the polygon must be simple)"); none when usable: >= 3 finite vertices, no two consecutive
/// equal, whose edges do not cross, not all collinear.
std::vector<std::string> simple_polygon_problems(const std::vector<Vec2>& v, const std::string& noun);

}  // namespace shapeform::core
