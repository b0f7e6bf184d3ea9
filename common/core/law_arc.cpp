#include "law_arc.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace shapeform::core {

namespace {
constexpr double kTwoPi = 6.283185307179586476925286766559;
}  // namespace

Vec2 arc_velocity(const ShapeSpec& s, const Curve& curve, const ArcParams& p, std::int32_t self_id,
                  const Vec2& x, const std::vector<Neighbour>& nbrs) {
  const Projection me = closest_point(s, curve, x);
  const double length = s.scale * curve.length();
  const bool closed = curve.closed();
  const bool infinite = !std::isfinite(length);
  const auto at = [&](double arc) { return to_world(s, curve.at(arc / s.scale)); };

  // Every agent heard, with its arc length, in a deterministic order (arc length, then id).
  thread_local std::vector<std::pair<double, std::int32_t>> all;
  all.clear();
  all.emplace_back(me.s, self_id);
  for (const Neighbour& n : nbrs)
    all.emplace_back(std::isfinite(n.s) ? n.s : closest_point(s, curve, n.x).s, n.id);
  std::sort(all.begin(), all.end());
  const int count = static_cast<int>(all.size());
  int rank = 0;
  while (all[rank].second != self_id) ++rank;

  double slot = 0.0, error = 0.0;
  if (count > 1) {
    if (closed) {
      // Slots L/N apart; their common offset is the circular mean of (s_j - rank_j L/N), which the
      // motion leaves unchanged, so every agent agrees on it from the same data.
      slot = length / count;
      double sx = 0.0, sy = 0.0;
      for (int k = 0; k < count; ++k) {
        const double ang = kTwoPi * (all[k].first - k * slot) / length;
        sx += std::cos(ang);
        sy += std::sin(ang);
      }
      const double offset = length / kTwoPi * std::atan2(sy, sx);
      error = std::remainder(offset + rank * slot - me.s, length);
    } else if (infinite) {
      // An infinite line: a finite row at the commanded spacing, centred where the swarm is.
      slot = p.spacing;
      double offset = 0.0;
      for (int k = 0; k < count; ++k) offset += all[k].first - k * slot;
      offset /= count;
      error = offset + rank * slot - me.s;
    } else {
      slot = length / (count - 1);  // an open curve: from end to end
      error = rank * slot - me.s;
    }
  }
  // Move toward the curve point a bounded step ahead along the curve: on a curved shape the step never
  // exceeds half a slot (so agents keep their order) nor a quarter of the shape (so the chord stays
  // near the curve). On the infinite line the chord is the curve: no bound is needed.
  double step = p.k_tangent * error;
  if (count > 1 && !infinite) {
    const double cap = std::min(0.5 * slot, 0.25 * shape_size(s, curve));
    step = std::clamp(step, -cap, cap);
  }
  const Vec2 q = count > 1 ? at(me.s + step) : me.point;
  return p.k_normal * (q - x);
}

}  // namespace shapeform::core
