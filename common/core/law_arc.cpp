#include "law_arc.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

namespace shapeform::core {

namespace {
constexpr double kTwoPi = 6.283185307179586476925286766559;

/// Every agent heard, with its arc length, in a deterministic order (arc length, then id).
using ArcList = std::vector<std::pair<double, std::int32_t>>;

/// What every agent of one arc list agrees on: the slots and their common offset, computed once from
/// the sorted list (the same data gives the same bits to every agent that holds it).
struct Layout {
  int count = 0;
  double length = 0.0;  ///< the shape's length (infinite for the line)
  bool closed = false, infinite = false;
  double slot = 0.0;    ///< arc length between neighbouring slots
  double offset = 0.0;  ///< where slot 0 is (closed curve, infinite line)
  double cap = 0.0;     ///< bound of a step along a finite curve
};

Layout layout(const ShapeSpec& s, const Curve& curve, const ArcParams& p, const ArcList& all) {
  Layout l;
  l.length = s.scale * curve.length();
  l.closed = curve.closed();
  l.infinite = !std::isfinite(l.length);
  l.count = static_cast<int>(all.size());
  const int count = l.count;
  if (count > 1) {
    if (l.closed) {
      // Slots L/N apart; their common offset is the circular mean of (s_j - rank_j L/N), which the
      // motion leaves unchanged, so every agent agrees on it from the same data.
      l.slot = l.length / count;
      double sx = 0.0, sy = 0.0;
      for (int k = 0; k < count; ++k) {
        const double ang = kTwoPi * (all[k].first - k * l.slot) / l.length;
        sx += std::cos(ang);
        sy += std::sin(ang);
      }
      l.offset = l.length / kTwoPi * std::atan2(sy, sx);
    } else if (l.infinite) {
      // An infinite line: a finite row at the commanded spacing, centred where the swarm is.
      l.slot = p.spacing;
      double offset = 0.0;
      for (int k = 0; k < count; ++k) offset += all[k].first - k * l.slot;
      l.offset = offset / count;
    } else {
      l.slot = l.length / (count - 1);  // an open curve: from end to end
    }
    if (!l.infinite) l.cap = std::min(0.5 * l.slot, 0.25 * shape_size(s, curve));
  }
  return l;
}

/// The velocity of the agent at x (projected to me) holding `rank` in the list that gave l.
Vec2 velocity_at(const ShapeSpec& s, const Curve& curve, const ArcParams& p, const Layout& l, int rank,
                 const Projection& me, const Vec2& x) {
  double error = 0.0;
  if (l.count > 1) {
    if (l.closed) error = std::remainder(l.offset + rank * l.slot - me.s, l.length);
    else if (l.infinite) error = l.offset + rank * l.slot - me.s;
    else error = rank * l.slot - me.s;
  }
  // Move toward the curve point a bounded step ahead along the curve: on a curved shape the step never
  // exceeds half a slot (so agents keep their order) nor a quarter of the shape (so the chord stays
  // near the curve). On the infinite line the chord is the curve: no bound is needed.
  double step = p.k_tangent * error;
  if (l.count > 1 && !l.infinite) step = std::clamp(step, -l.cap, l.cap);
  const Vec2 q = l.count > 1 ? to_world(s, curve.at((me.s + step) / s.scale)) : me.point;
  return p.k_normal * (q - x);
}

}  // namespace

void sort_by_arc(std::vector<std::pair<double, std::int32_t>>& all) {
  // Ids are looked up in small tables; far outside the swarm's id range, a plain sort.
  constexpr std::int32_t kMaxIndexedId = 1 << 20;
  thread_local std::vector<std::int32_t> last;       // ids in the order of the previous sorted list
  thread_local std::vector<std::uint32_t> in, used;  // per id: the call it was in `all`, taken already
  thread_local std::vector<double> arc_of_id;
  thread_local std::uint32_t call = 0;
  thread_local ArcList scratch;
  ++call;
  if (call == 0) {  // wrapped: forget the marks
    std::fill(in.begin(), in.end(), 0u);
    std::fill(used.begin(), used.end(), 0u);
    call = 1;
  }
  bool indexed = true;
  for (const auto& [arc, id] : all) {
    if (id < 0 || id > kMaxIndexedId) {
      indexed = false;
      break;
    }
    const auto k = static_cast<std::size_t>(id);
    if (k >= in.size()) {
      in.resize(k + 1, 0u);
      used.resize(k + 1, 0u);
      arc_of_id.resize(k + 1, 0.0);
    }
    if (in[k] == call) {  // an id twice: no order to reuse
      indexed = false;
      break;
    }
    in[k] = call;
    arc_of_id[k] = arc;
  }
  if (!indexed) {
    std::sort(all.begin(), all.end());
    last.clear();
    return;
  }
  // The previous order first (ids still present), then the new ids: nearly sorted while the agents
  // keep their order along the shape, so an insertion sort finishes in about one pass.
  scratch.clear();
  for (const std::int32_t id : last) {
    const auto k = static_cast<std::size_t>(id);
    if (k < in.size() && in[k] == call && used[k] != call) {
      used[k] = call;
      scratch.emplace_back(arc_of_id[k], id);
    }
  }
  for (const auto& e : all)
    if (used[static_cast<std::size_t>(e.second)] != call) scratch.push_back(e);
  // Insertion sort with a budget of moves: past it (a reshuffle, the first call), a plain sort. The
  // pairs are distinct, so both give the one sorted order.
  std::size_t moves = 0;
  const std::size_t budget = 8 * scratch.size() + 64;
  for (std::size_t i = 1; i < scratch.size() && moves <= budget; ++i) {
    const auto v = scratch[i];
    std::size_t j = i;
    for (; j > 0 && v < scratch[j - 1]; --j) scratch[j] = scratch[j - 1];
    scratch[j] = v;
    moves += i - j;
  }
  if (moves > budget) std::sort(scratch.begin(), scratch.end());
  all.swap(scratch);
  last.clear();
  for (const auto& e : all) last.push_back(e.second);
}

namespace {

/// A neighbour's arc length: the one it published when finite, else its position projected.
double arc_of(const ShapeSpec& s, const Curve& curve, const Neighbour& n) {
  return std::isfinite(n.s) ? n.s : closest_point(s, curve, n.x).s;
}

}  // namespace

Vec2 arc_velocity(const ShapeSpec& s, const Curve& curve, const ArcParams& p, std::int32_t self_id,
                  const Vec2& x, const std::vector<Neighbour>& nbrs) {
  const Projection me = closest_point(s, curve, x);
  thread_local ArcList all;
  all.clear();
  all.emplace_back(me.s, self_id);
  for (const Neighbour& n : nbrs) all.emplace_back(arc_of(s, curve, n), n.id);
  sort_by_arc(all);
  int rank = 0;
  while (all[rank].second != self_id) ++rank;
  return velocity_at(s, curve, p, layout(s, curve, p, all), rank, me, x);
}

void arc_velocities(const ShapeSpec& s, const Curve& curve, const ArcParams& p, const std::vector<Neighbour>& hosted,
                    const std::vector<Neighbour>& others, std::vector<Vec2>& out) {
  thread_local std::vector<Projection> me;
  thread_local ArcList all;
  me.clear();
  all.clear();
  for (const Neighbour& h : hosted) {
    me.push_back(closest_point(s, curve, h.x));
    all.emplace_back(me.back().s, h.id);
  }
  for (const Neighbour& n : others) all.emplace_back(arc_of(s, curve, n), n.id);
  sort_by_arc(all);
  const Layout l = layout(s, curve, p, all);
  out.resize(hosted.size());
  for (std::size_t k = 0; k < hosted.size(); ++k) {
    // The pairs are distinct (ids are), so the first pair not below ours is ours: its rank.
    const std::pair<double, std::int32_t> mine{me[k].s, hosted[k].id};
    const int rank = static_cast<int>(std::lower_bound(all.begin(), all.end(), mine) - all.begin());
    out[k] = velocity_at(s, curve, p, l, rank, me[k], hosted[k].x);
  }
}

}  // namespace shapeform::core
