#include "polygon.hpp"

#include <algorithm>

namespace shapeform::core {

namespace {

/// Whether segments [a, b] and [c, d] meet (touching counts).
bool segments_meet(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const auto side = [](const Vec2& p, const Vec2& q, const Vec2& r) {
    const double v = cross(q - p, r - p);
    return v > 0.0 ? 1 : (v < 0.0 ? -1 : 0);
  };
  const auto on = [](const Vec2& p, const Vec2& q, const Vec2& r) {  // r on [p, q], collinear given
    return std::min(p.x(), q.x()) <= r.x() && r.x() <= std::max(p.x(), q.x()) &&
           std::min(p.y(), q.y()) <= r.y() && r.y() <= std::max(p.y(), q.y());
  };
  const int d1 = side(a, b, c), d2 = side(a, b, d), d3 = side(c, d, a), d4 = side(c, d, b);
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  return (d1 == 0 && on(a, b, c)) || (d2 == 0 && on(a, b, d)) || (d3 == 0 && on(c, d, a)) ||
         (d4 == 0 && on(c, d, b));
}

}  // namespace

double twice_area(const std::vector<Vec2>& v) {
  double a = 0.0;
  for (std::size_t i = 0; i < v.size(); ++i) a += cross(v[i], v[(i + 1) % v.size()]);
  return a;
}

std::vector<std::string> simple_polygon_problems(const std::vector<Vec2>& v, const std::string& noun) {
  std::vector<std::string> out;
  if (v.size() < 3) {
    out.push_back(noun + " needs >= 3 vertices, got " + std::to_string(v.size()));
    return out;
  }
  for (const Vec2& p : v)
    if (!p.allFinite()) {
      out.push_back(noun + " vertices must be finite");
      return out;
    }
  for (std::size_t i = 0; i < v.size(); ++i)
    if (v[i] == v[(i + 1) % v.size()])
      out.push_back(noun + " vertices " + std::to_string(i) + " and " + std::to_string((i + 1) % v.size()) +
                    " are equal");
  if (!out.empty()) return out;
  const std::size_t n = v.size();
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // adjacent through the closing edge
      if (segments_meet(v[i], v[(i + 1) % n], v[j], v[(j + 1) % n])) {
        out.push_back(noun + " edges " + std::to_string(i) + " and " + std::to_string(j) + " cross (the " +
                      noun + " must be simple)");
        return out;
      }
    }
  if (twice_area(v) == 0.0) out.push_back(noun + " vertices are all on one line (no area)");
  return out;
}

}  // namespace shapeform::core
