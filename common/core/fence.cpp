#include "fence.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "params.hpp"
#include "polygon.hpp"

namespace shapeform::core {

namespace {

/// The outward half-planes of a counter-clockwise convex polygon's edges, each shrunk by margin.
std::vector<HalfPlane> sides(const std::vector<Vec2>& v, double margin) {
  std::vector<HalfPlane> out;
  out.reserve(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    const Vec2 e = v[(i + 1) % v.size()] - v[i];
    HalfPlane h;
    h.n = Vec2(e.y(), -e.x()) / e.norm();
    h.b = h.n.dot(v[i]) - margin;
    out.push_back(h);
  }
  return out;
}

/// The convex polygon v cut by the half-planes (Sutherland-Hodgman); fewer than 3 vertices when
/// nothing of positive area is left.
std::vector<Vec2> clip(std::vector<Vec2> v, const std::vector<HalfPlane>& hs) {
  for (const HalfPlane& h : hs) {
    std::vector<Vec2> out;
    for (std::size_t i = 0; i < v.size(); ++i) {
      const Vec2& a = v[i];
      const Vec2& c = v[(i + 1) % v.size()];
      const double da = h.n.dot(a) - h.b;
      const double dc = h.n.dot(c) - h.b;
      if (da <= 0.0) out.push_back(a);
      if ((da < 0.0 && dc > 0.0) || (da > 0.0 && dc < 0.0)) out.push_back(a + (c - a) * (da / (da - dc)));
    }
    v = std::move(out);
    if (v.size() < 3) return {};
  }
  if (!(twice_area(v) > 0.0)) return {};
  return v;
}

/// The point of a counter-clockwise convex polygon nearest x (x itself inside).
Vec2 nearest_in(const std::vector<Vec2>& v, const Vec2& x) {
  bool in = true;
  for (std::size_t i = 0; i < v.size() && in; ++i) in = cross(v[(i + 1) % v.size()] - v[i], x - v[i]) >= 0.0;
  if (in) return x;
  Vec2 best = v.front();
  double best_d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < v.size(); ++i) {
    const Vec2 q = segment_point(v[i], v[(i + 1) % v.size()], x);
    const double d = (q - x).squaredNorm();
    if (d < best_d) best_d = d, best = q;
  }
  return best;
}

}  // namespace

std::vector<std::string> fence_problems(const std::vector<Vec2>& fence, double workspace) {
  std::vector<std::string> out;
  if (fence.empty()) return out;
  out = simple_polygon_problems(fence, "fence");
  if (!out.empty()) return out;
  // Simple and of positive area: convex when it turns one way at every vertex (a vertex on the line of
  // its neighbours, going on, is a straight corner; going back is a spike).
  const double sense = twice_area(fence) > 0.0 ? 1.0 : -1.0;
  const std::size_t n = fence.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 e0 = fence[(i + 1) % n] - fence[i];
    const Vec2 e1 = fence[(i + 2) % n] - fence[(i + 1) % n];
    const double turn = sense * cross(e0, e1);
    if (turn < 0.0 || (turn == 0.0 && e0.dot(e1) < 0.0)) {
      out.push_back("a fence must be convex (it turns back at vertex " + std::to_string((i + 1) % n) +
                    "); cut the rest out with safety.keep_out");
      break;
    }
  }
  std::vector<std::string> outside;
  for (std::size_t i = 0; i < n; ++i)
    if (!(std::abs(fence[i].x()) <= workspace && std::abs(fence[i].y()) <= workspace))
      outside.push_back(std::to_string(i) + " (" + params::format_number(fence[i].x()) + ", " +
                        params::format_number(fence[i].y()) + ")");
  if (!outside.empty())
    out.push_back((outside.size() == 1 ? "fence vertex " : "fence vertices ") + params::join(outside, ", ") +
                  (outside.size() == 1 ? " is" : " are") +
                  " outside the workspace [-w, w]^2 (safety.workspace = " + params::format_number(workspace) +
                  "): move " + (outside.size() == 1 ? "it" : "them") + " in or widen safety.workspace");
  return out;
}

std::vector<Vec2> fence_polygon(const Command& cmd) {
  if (cmd.fence.empty()) {
    const double w = cmd.workspace;
    return {Vec2(-w, -w), Vec2(w, -w), Vec2(w, w), Vec2(-w, w)};
  }
  std::vector<Vec2> v = cmd.fence;
  if (twice_area(v) < 0.0) std::reverse(v.begin(), v.end());
  return v;
}

double beyond_fence(const Command& cmd, const Vec2& x) {
  if (cmd.fence.empty()) return (x.cwiseAbs() - Vec2(cmd.workspace, cmd.workspace)).cwiseMax(0.0).norm();
  const std::vector<Vec2> v = fence_polygon(cmd);
  bool in = true;
  for (const HalfPlane& h : sides(v, 0.0)) in = in && h.contains(x);
  if (in) return 0.0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < v.size(); ++i)
    best = std::min(best, (segment_point(v[i], v[(i + 1) % v.size()], x) - x).norm());
  return best;
}

Vec2 fence_return_point(const Command& cmd, const Vec2& x) {
  const std::vector<Vec2> v = fence_polygon(cmd);
  const double margin = std::max(0.0, cmd.fence_margin);
  const std::vector<HalfPlane> shrunk = sides(v, margin);
  if (std::all_of(shrunk.begin(), shrunk.end(), [&x](const HalfPlane& h) { return h.contains(x); })) return x;
  std::vector<Vec2> inner = clip(v, shrunk);
  if (inner.empty()) {
    // Thinner than 2 margin: the largest shrink that leaves an area (bisection toward the deepest
    // points; 60 halvings reach the rounding of any margin).
    double lo = 0.0, hi = margin;
    for (int k = 0; k < 60; ++k) {
      const double mid = 0.5 * (lo + hi);
      (clip(v, sides(v, mid)).empty() ? hi : lo) = mid;
    }
    inner = clip(v, sides(v, lo));
    if (inner.empty()) inner = v;
  }
  return nearest_in(inner, x);
}

std::vector<HalfPlane> fence_half_planes(const Command& cmd) {
  return sides(fence_polygon(cmd), std::max(0.0, cmd.fence_margin));
}

}  // namespace shapeform::core
