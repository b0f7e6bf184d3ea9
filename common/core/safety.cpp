#include "safety.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "fence.hpp"
#include "polygon.hpp"

namespace shapeform::core {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Rounding allowance of a constraint n . p <= b: relative to the size of its numbers.
double tol(double b) { return 1e-12 * (1.0 + std::abs(b)); }

bool convex_ccw(const std::vector<Vec2>& v) {
  for (std::size_t i = 0; i < v.size(); ++i) {
    const Vec2& a = v[i];
    const Vec2& b = v[(i + 1) % v.size()];
    const Vec2& c = v[(i + 2) % v.size()];
    if (cross(b - a, c - b) < 0.0) return false;
  }
  return true;
}

/// Whether p is inside or on the counter-clockwise triangle abc.
bool in_triangle(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& p) {
  return cross(b - a, p - a) >= 0.0 && cross(c - b, p - b) >= 0.0 && cross(a - c, p - c) >= 0.0;
}

/// The convex hull of points, counter-clockwise (Andrew's monotone chain).
std::vector<Vec2> hull(std::vector<Vec2> v) {
  std::sort(v.begin(), v.end(),
            [](const Vec2& a, const Vec2& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  std::vector<Vec2> h(2 * v.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    while (k >= 2 && cross(h[k - 1] - h[k - 2], v[i] - h[k - 2]) <= 0.0) --k;
    h[k++] = v[i];
  }
  for (std::size_t i = v.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 1] - h[k - 2], v[i] - h[k - 2]) <= 0.0) --k;
    h[k++] = v[i];
  }
  h.resize(k > 1 ? k - 1 : k);
  return h;
}

/// A simple counter-clockwise polygon cut into triangles (ear clipping, O(n^3) at worst: zones are
/// cut once per command). Collinear vertices are dropped.
std::vector<std::vector<Vec2>> triangles(std::vector<Vec2> v) {
  std::vector<std::vector<Vec2>> out;
  while (v.size() > 3) {
    const std::size_t n = v.size();
    bool cut = false;
    for (std::size_t i = 0; i < n && !cut; ++i) {
      const Vec2& a = v[(i + n - 1) % n];
      const Vec2& b = v[i];
      const Vec2& c = v[(i + 1) % n];
      const double turn = cross(b - a, c - b);
      if (turn == 0.0) {  // b lies on the line a-c: no triangle, drop it
        v.erase(v.begin() + static_cast<std::ptrdiff_t>(i));
        cut = true;
        break;
      }
      if (turn < 0.0) continue;  // a reflex vertex is no ear
      bool empty = true;
      for (std::size_t k = 0; k < n && empty; ++k) {
        if (k == i || k == (i + n - 1) % n || k == (i + 1) % n) continue;
        if (in_triangle(a, b, c, v[k])) empty = false;
      }
      if (!empty) continue;
      out.push_back({a, b, c});
      v.erase(v.begin() + static_cast<std::ptrdiff_t>(i));
      cut = true;
    }
    if (!cut) {  // rounding found no ear: the rest's convex hull (it covers the rest: conservative)
      out.push_back(hull(v));
      return out;
    }
  }
  if (v.size() == 3 && cross(v[1] - v[0], v[2] - v[1]) > 0.0) out.push_back(v);
  return out;
}

/// Clockwise turn of v by `deg` degrees.
Vec2 turn_right(const Vec2& v, double deg) {
  const double a = -deg * kPi / 180.0;
  const double c = std::cos(a), s = std::sin(a);
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

/// The closest points of the segments [a0, a1] and [b0, b1]: p on the first, q on the second (one
/// point where they cross).
void closest_points(const Vec2& a0, const Vec2& a1, const Vec2& b0, const Vec2& b1, Vec2& p, Vec2& q) {
  const Vec2 ea = a1 - a0, eb = b1 - b0;
  const double den = cross(ea, eb);
  if (den != 0.0) {
    const double t = cross(b0 - a0, eb) / den, u = cross(b0 - a0, ea) / den;
    if (t >= 0.0 && t <= 1.0 && u >= 0.0 && u <= 1.0) {
      p = q = a0 + t * ea;
      return;
    }
  }
  // Apart (or parallel): the nearest pair has an end of one segment in it.
  const Vec2 cand[4][2] = {{a0, segment_point(b0, b1, a0)},
                           {a1, segment_point(b0, b1, a1)},
                           {segment_point(a0, a1, b0), b0},
                           {segment_point(a0, a1, b1), b1}};
  double best = std::numeric_limits<double>::infinity();
  for (const auto& c : cand) {
    const double l = (c[1] - c[0]).squaredNorm();
    if (l < best) best = l, p = c[0], q = c[1];
  }
}

/// The point of the segment [a, b] nearest a convex piece (one inside it when the segment enters it).
Vec2 nearest_on_segment(const ConvexZone& z, const Vec2& a, const Vec2& b) {
  if (z.circle) return segment_point(a, b, z.centre);
  Vec2 best_p = a;
  double best = std::numeric_limits<double>::infinity();
  const auto take = [&](const Vec2& on, double dist) {
    if (dist < best) best = dist, best_p = on;
  };
  take(a, distance(z, a));
  take(b, distance(z, b));
  const std::size_t n = z.vertices.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& v = z.vertices[i];
    Vec2 on, at;
    closest_points(a, b, v, z.vertices[(i + 1) % n], on, at);
    take(on, (at - on).norm());
  }
  return best_p;
}

}  // namespace

std::vector<std::string> keep_out_problems(const KeepOutZone& z) {
  std::vector<std::string> out;
  if (z.kind == KeepOutZone::Kind::Circle) {
    if (!z.centre.allFinite()) out.push_back("circle centre must be finite");
    if (!std::isfinite(z.radius) || z.radius <= 0.0) out.push_back("circle radius must be > 0");
    return out;
  }
  return simple_polygon_problems(z.vertices, "polygon");
}

std::vector<ConvexZone> convex_pieces(const std::vector<KeepOutZone>& zones) {
  std::vector<ConvexZone> out;
  for (std::size_t k = 0; k < zones.size(); ++k) {
    const KeepOutZone& z = zones[k];
    if (!keep_out_problems(z).empty()) continue;
    ConvexZone piece;
    piece.zone = static_cast<int>(k);
    if (z.kind == KeepOutZone::Kind::Circle) {
      piece.centre = z.centre;
      piece.radius = z.radius;
      out.push_back(piece);
      continue;
    }
    std::vector<Vec2> v = z.vertices;
    if (twice_area(v) < 0.0) std::reverse(v.begin(), v.end());
    piece.circle = false;
    const auto add = [&](std::vector<Vec2> poly) {
      piece.vertices = std::move(poly);
      piece.centre = Vec2::Zero();
      for (const Vec2& p : piece.vertices) piece.centre += p;
      piece.centre /= static_cast<double>(piece.vertices.size());
      out.push_back(piece);
    };
    if (convex_ccw(v))
      add(v);
    else
      for (auto& t : triangles(v)) add(std::move(t));
  }
  return out;
}

double depth(const KeepOutZone& z, const Vec2& p) {
  if (z.kind == KeepOutZone::Kind::Circle) return std::max(0.0, z.radius - (p - z.centre).norm());
  const std::vector<Vec2>& v = z.vertices;
  bool in = false;  // ray casting: a crossing of the ray to +x1 per edge that straddles p's x2
  double edge = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0, j = v.size() - 1; i < v.size(); j = i++) {
    if ((v[i].y() > p.y()) != (v[j].y() > p.y()) &&
        p.x() < (v[j].x() - v[i].x()) * (p.y() - v[i].y()) / (v[j].y() - v[i].y()) + v[i].x())
      in = !in;
    edge = std::min(edge, (segment_point(v[j], v[i], p) - p).norm());
  }
  return in ? edge : 0.0;
}

bool inside(const ConvexZone& z, const Vec2& p) {
  if (z.circle) return (p - z.centre).norm() <= z.radius;
  const std::size_t n = z.vertices.size();
  for (std::size_t i = 0; i < n; ++i)
    if (cross(z.vertices[(i + 1) % n] - z.vertices[i], p - z.vertices[i]) < 0.0) return false;
  return true;
}

double distance(const ConvexZone& z, const Vec2& p) {
  if (z.circle) return std::max(0.0, (p - z.centre).norm() - z.radius);
  if (inside(z, p)) return 0.0;
  double best = std::numeric_limits<double>::infinity();
  const std::size_t n = z.vertices.size();
  for (std::size_t i = 0; i < n; ++i)
    best = std::min(best, (segment_point(z.vertices[i], z.vertices[(i + 1) % n], p) - p).norm());
  return best;
}

HalfPlane separation_half_plane(std::int32_t self_id, const Vec2& x, const SafetyNeighbour& j, double d,
                                bool& broken) {
  const Vec2 diff = j.x - x;
  const double dist = diff.norm();
  HalfPlane h;
  h.n = dist > 0.0 ? Vec2(diff / dist) : Vec2(self_id < j.id ? 1.0 : -1.0, 0.0);
  broken = dist < d - 1e-9 * (1.0 + d);  // by more than rounding: a pair the filter keeps at d is not broken
  const double margin = j.max_speed * j.age_s;
  const double nx = h.n.dot(x);
  // The agent's half of the gap beyond d, less the neighbour's possible motion; a margin that is not
  // a finite non-negative number (an unknown speed or age) leaves only "do not approach".
  const double half = std::isfinite(margin) && margin >= 0.0 ? 0.5 * (dist - d) - margin : -1.0;
  h.b = half > 0.0 ? nx + half : nx;
  return h;
}

HalfPlane keep_out_half_plane(const ConvexZone& z, const Vec2& x, bool& in) {
  HalfPlane h;
  if (z.circle) {
    // The tangent at the circle's point nearest x (the direction to the centre is well defined as
    // long as x is not the centre); inside, the line through x: no nearer the centre.
    const Vec2 to = z.centre - x;
    const double l = to.norm();
    h.n = l > 0.0 ? Vec2(to / l) : Vec2::UnitX();
    h.b = h.n.dot(x) + std::max(0.0, l - z.radius);
    in = l < z.radius * (1.0 - 1e-12);
    return h;
  }
  // The polygon's face x is most outside of (largest signed distance s to its line): the polygon lies
  // behind every face's line, so the outer side of that one is safe, and holds x when s >= 0. Agents
  // pushed onto a face by the filter sit at s = 0, where only a face's line is well conditioned. At a
  // vertex (two faces at s = 0) either face's line would leave the other face's line open, and a
  // convex piece of a larger polygon may share that face with the next piece (a diagonal inside the
  // polygon): the line through the vertex along the sum of both faces' normals touches the piece at the
  // vertex alone.
  const std::size_t n = z.vertices.size();
  const double tol_s = 1e-9 * (1.0 + x.norm());
  std::vector<double> s_of(n);
  std::vector<Vec2> m_of(n);
  double s_max = -std::numeric_limits<double>::infinity();
  Vec2 q = x;
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& a = z.vertices[i];
    const Vec2& b = z.vertices[(i + 1) % n];
    const Vec2 e = b - a;
    m_of[i] = Vec2(e.y(), -e.x()) / e.norm();  // outward (counter-clockwise polygon)
    s_of[i] = m_of[i].dot(x - a);
    s_max = std::max(s_max, s_of[i]);
    const Vec2 c = segment_point(a, b, x);
    const double dd = (c - x).norm();
    if (dd < nearest) nearest = dd, q = c;
  }
  in = s_max < -1e-12 * (1.0 + x.norm());
  if (s_max > 0.0 && nearest > tol_s) {
    // Clearly outside: the supporting line at the nearest point (beside a vertex it is less
    // conservative than a face's).
    h.n = (q - x) / nearest;
    h.b = h.n.dot(q);
    return h;
  }
  Vec2 m = Vec2::Zero();
  std::size_t faces = 0, face = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (s_of[i] >= s_max - tol_s) m += m_of[i], ++faces, face = i;
  if (faces == 1) {
    h.n = -m_of[face];
    // On or behind the face: its line; inside: no deeper than x.
    h.b = std::max(h.n.dot(z.vertices[face]), h.n.dot(x));
    return h;
  }
  const double l = m.norm();
  h.n = l > 0.0 ? Vec2(-m / l) : Vec2(-m_of[face]);
  h.b = h.n.dot(x);
  return h;
}

Vec2 closest_feasible(const Vec2& w, const std::vector<HalfPlane>& h, const Vec2& c, double r) {
  // Seidel's incremental method for a strictly convex objective: the optimum of the first k
  // constraints either satisfies constraint k + 1 or lies on its line, where the problem is one
  // interval of the line (clipped by the earlier constraints and the disc), solved exactly.
  const bool disc = r > 0.0;
  const Vec2 wc = w - c;
  const double lw = wc.norm();
  Vec2 p = disc && lw > r ? Vec2(c + (r / lw) * wc) : w;
  // Only a line nearer c than the optimum can be (|opt - c| <= |w - c|, c being feasible) matters.
  const double reach = disc ? std::min(r, lw) : lw;
  thread_local std::vector<const HalfPlane*> act;
  act.clear();
  for (const HalfPlane& k : h)
    if (k.b - k.n.dot(c) <= reach + tol(k.b)) act.push_back(&k);
  // Tightest first: the constraints most likely to bind come early, so later ones rarely move p.
  std::sort(act.begin(), act.end(),
            [&c](const HalfPlane* a, const HalfPlane* b) { return a->b - a->n.dot(c) < b->b - b->n.dot(c); });
  for (std::size_t k = 0; k < act.size(); ++k) {
    const HalfPlane& hk = *act[k];
    if (hk.contains(p, tol(hk.b))) continue;
    const Vec2 foot = w - (hk.n.dot(w) - hk.b) * hk.n;  // w's projection on the line
    const Vec2 u(-hk.n.y(), hk.n.x());
    double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
    bool empty = false;
    for (std::size_t j = 0; j < k && !empty; ++j) {
      const HalfPlane& hj = *act[j];
      const double a = hj.n.dot(u);
      const double s = hj.b - hj.n.dot(foot);
      if (std::abs(a) <= 1e-15) {
        if (s < -tol(hj.b)) empty = true;
      } else if (a > 0.0) {
        hi = std::min(hi, s / a);
      } else {
        lo = std::max(lo, s / a);
      }
    }
    if (disc && !empty) {
      // |foot + t u - c|^2 <= r^2: t^2 + 2 t u.(foot - c) + |foot - c|^2 - r^2 <= 0
      const Vec2 fc = foot - c;
      const double bq = u.dot(fc);
      const double disc2 = bq * bq - (fc.squaredNorm() - r * r);
      if (disc2 < 0.0) {
        empty = true;
      } else {
        const double root = std::sqrt(disc2);
        lo = std::max(lo, -bq - root);
        hi = std::min(hi, -bq + root);
      }
    }
    if (empty || lo > hi) {
      if (empty || lo - hi > 1e-12 * (1.0 + std::abs(lo))) return c;  // rounding left nothing: stand still
      hi = lo = 0.5 * (lo + hi);
    }
    p = foot + std::clamp(0.0, lo, hi) * u;
  }
  return p;
}

bool filters(const Command& cmd) {
  return cmd.min_separation > 0.0 || !cmd.keep_out.empty() || !cmd.fence.empty() || cmd.fence_margin > 0.0;
}

SafetyParams safety_params(const Command& cmd, const VehicleParams& vehicle) {
  SafetyParams p;
  p.min_separation = cmd.min_separation;
  p.fence = fence_half_planes(cmd);
  const double law = cmd.max_speed > 0.0 ? cmd.max_speed * cmd.dt : 0.0;
  const double own =
      vehicle.max_speed > 0.0 ? vehicle.max_speed * cmd.dt * vehicle.seconds_per_model_time : 0.0;
  p.max_step = law > 0.0 && own > 0.0 ? std::min(law, own) : std::max(law, own);
  p.braking = vehicle.model == VehicleModel::DoubleIntegrator;
  return p;
}

bool SafetyOutcome::holds(const Vec2& x1, const Vec2& stop1) const {
  if (!braking) return in_cell(x1);
  const Vec2 end = from + brake;
  const double t = 1e-12 * (1.0 + from.norm() + brake.norm());
  for (const Vec2& q : {x1, stop1}) {
    const double off = (segment_point(from, end, q) - q).norm();
    if (still ? off > t : off > grow + t) return false;
    if (away != Vec2::Zero()) {
      // In the shadow {b - s away : b on the segment, s >= 0}: the ray from q along `away` meets it.
      Vec2 on, at;
      closest_points(from, end, q, q + (off + brake.norm() + 1.0) * away, on, at);
      if ((at - on).norm() > t) return false;
    }
    for (const HalfPlane& h : cell)
      if (!h.contains(q, tol(h.b))) return false;
  }
  return true;
}

bool SafetyOutcome::in_cell(const Vec2& p) const {
  if (still) return (p - from).norm() <= 1e-12 * (1.0 + from.norm());
  for (const HalfPlane& h : cell)
    if (!h.contains(p, tol(h.b))) return false;
  return max_step <= 0.0 || (p - from).norm() <= max_step * (1.0 + 1e-12) + 1e-15;
}

SafetyOutcome safety_filter(const SafetyParams& p, SafetyState& state, std::int32_t self_id, const Vec2& x,
                            const Vec2& wanted, const std::vector<SafetyNeighbour>& nbrs,
                            const std::vector<ConvexZone>& zones, const Vec2& brake) {
  SafetyOutcome out;
  out.from = x;
  out.max_step = p.max_step;
  out.braking = p.braking;
  // The agent's braking segment [x, stop] (a point unless braking).
  const Vec2 stop = p.braking ? Vec2(x + brake) : x;
  out.brake = stop - x;
  const double d = p.min_separation;
  // Each constraint's source, for blocking_id / blocking_zone: >= 0 a neighbour's id, else -1 - zone.
  thread_local std::vector<std::int64_t> source;
  source.clear();
  out.cell.reserve(nbrs.size() + zones.size());
  Vec2 away = Vec2::Zero();
  double nearest_broken = std::numeric_limits<double>::infinity();
  // A stale sample's half-plane is not enough: the two agents' views differ, so their lines are not
  // parallel. The step then stays in the disc of radius (|x_j^ - x| - margin - d) / 2 about x as well:
  // with the neighbour doing the same (or keeping to its exact half-plane), each moves at most half the
  // true gap beyond d, whatever the angle (|x_j^ - x| <= D + margin).
  double reach = std::numeric_limits<double>::infinity();
  // A stale neighbour too near for any step (its disc has no room): straight away from it is still safe
  // (the true gap grows along -n as long as it exceeds the margin), so with exactly one such neighbour
  // the agent may back off along -n, which is how a deadlock between two of them is broken.
  int too_near = 0;
  Vec2 near_n = Vec2::Zero();
  std::int32_t near_id = -1;
  double reach_others = std::numeric_limits<double>::infinity();
  if (d > 0.0 && p.braking) {
    // Segments (see the header): the half-plane between the closest points, holding the own segment.
    for (const SafetyNeighbour& j : nbrs) {
      Vec2 pi, pj;
      closest_points(x, stop, j.x, j.x + j.brake, pi, pj);
      const Vec2 diff = pj - pi;
      const double gap = diff.norm();
      const Vec2 pos = j.x - x;
      const double dist = pos.norm();
      HalfPlane h;
      h.n = gap > 0.0 ? Vec2(diff / gap) : dist > 0.0 ? Vec2(pos / dist) : Vec2(self_id < j.id ? 1.0 : -1.0, 0.0);
      if (dist < d - 1e-9 * (1.0 + d)) {
        ++out.broken;
        away -= dist > 0.0 ? Vec2(pos / dist) : h.n;
        nearest_broken = std::min(nearest_broken, dist);
      }
      const double margin = j.max_speed * j.age_s + j.blur;
      const double top = std::max(h.n.dot(x), h.n.dot(stop));  // the own segment's farthest toward j
      if (!(std::isfinite(margin) && margin >= 0.0)) {
        h.b = top;
        reach = 0.0;
      } else {
        h.b = std::max(top, h.n.dot(pi) + std::max(0.0, 0.5 * (gap - d) - margin));
        const double room = 0.5 * (gap - margin - d);
        if (margin > 0.0) {
          reach = std::min(reach, std::max(0.0, room));
          if (room > 0.0) {
            reach_others = std::min(reach_others, room);
          } else if (gap > margin) {
            // Too near for any growth, but the true segment is beyond the margin: backing away is safe.
            ++too_near;
            near_n = h.n;
            near_id = j.id;
          } else {
            too_near += 2;
          }
        }
      }
      out.cell.push_back(h);
      source.push_back(j.id);
    }
  } else if (d > 0.0) {
    for (const SafetyNeighbour& j : nbrs) {
      bool broken = false;
      const HalfPlane h = separation_half_plane(self_id, x, j, d, broken);
      if (broken) {
        ++out.broken;
        away -= h.n;
        nearest_broken = std::min(nearest_broken, (j.x - x).norm());
      }
      const double margin = j.max_speed * j.age_s;
      if (!broken && margin != 0.0) {
        const double room = std::isfinite(margin) && margin > 0.0 ? 0.5 * ((j.x - x).norm() - margin - d) : -1.0;
        if (room > 0.0) {
          reach_others = std::min(reach_others, room);
        } else if (std::isfinite(margin) && margin > 0.0 && (j.x - x).norm() > margin) {
          ++too_near;
          near_n = h.n;
          near_id = j.id;
        } else {
          too_near += 2;  // no safe direction at all (an unknown margin, or within it)
        }
        reach = std::min(reach, std::max(room, 0.0));
      }
      out.cell.push_back(h);
      source.push_back(j.id);
    }
  }
  Vec2 exit = Vec2::Zero();  // out of the zones x is in (one set over it): away from their insides
  for (const ConvexZone& z : zones) {
    bool in = false;
    out.cell.push_back(keep_out_half_plane(z, x, in));
    if (p.braking && stop != x) {
      // The half-plane at the segment's point nearest the piece, widened to hold the whole segment.
      bool at_in = false;
      HalfPlane& h = out.cell.back();
      h = keep_out_half_plane(z, nearest_on_segment(z, x, stop), at_in);
      h.b = std::max({h.b, h.n.dot(x), h.n.dot(stop)});
    }
    source.push_back(-1 - static_cast<std::int64_t>(z.zone));
    if (in) {
      ++out.inside_zones;
      exit -= out.cell.back().n;
    }
  }
  // The fence's sides shrunk by its margin; one that x breaks (an agent outside: pushed by a vehicle's
  // momentum, placed there, a fence moved under it) becomes "go no further out", so x stays in the cell.
  for (const HalfPlane& h : p.fence) {
    out.cell.push_back({h.n, p.braking ? std::max({h.b, h.n.dot(x), h.n.dot(stop)}) : std::max(h.b, h.n.dot(x))});
    source.push_back(std::numeric_limits<std::int64_t>::min());
  }
  if (reach < std::numeric_limits<double>::infinity())
    out.max_step = p.max_step > 0.0 ? std::min(p.max_step, reach) : reach;
  const bool frozen = reach == 0.0;  // a stale neighbour too near to move at all: stand still ...
  const bool back_off = frozen && too_near == 1;  // ... or back straight away from the one
  double ray = 0.0;                                // how far it may back off
  if (back_off) {
    ray = std::min(p.max_step > 0.0 ? p.max_step : std::numeric_limits<double>::infinity(), reach_others);
    for (const HalfPlane& h : out.cell) {
      const double toward = -h.n.dot(near_n);  // the rate at which backing off approaches h's line
      if (toward > 0.0) ray = std::min(ray, std::max(0.0, (h.b - h.n.dot(x)) / toward));
    }
    if (!std::isfinite(ray)) ray = 0.0;
    if (p.braking) {
      // The new segment stays in the own segment's shadow away from the neighbour (SafetyOutcome::away),
      // within the other stale neighbours' room.
      out.away = near_n;
      out.grow = reach_others;
    } else {
      // The cell becomes the ray: the line through x along n (both sides) and the disc of radius `ray`.
      const Vec2 side(-near_n.y(), near_n.x());
      out.cell.push_back({side, side.dot(x)});
      out.cell.push_back({-side, -side.dot(x)});
      source.push_back(near_id);
      source.push_back(near_id);
    }
    out.max_step = ray;
  }
  out.still = frozen && !back_off;
  if (p.braking && !back_off) out.grow = reach;
  // While sidestepping, an agent that can only back off does (the right-hand turn has no room).
  const auto solve = [&](const Vec2& goal) {
    if (!frozen) return closest_feasible(goal, out.cell, x, out.max_step);
    if (!back_off) return x;
    const Vec2 g = out.sidestep ? Vec2(x - ray * near_n) : goal;
    return Vec2(x - std::clamp(-(g - x).dot(near_n), 0.0, ray) * near_n);
  };
  const Vec2 step = wanted - x;
  const double len = step.norm();
  Vec2 goal = wanted;
  if (out.broken > 0) {
    // The largest safe step away from the neighbours on top: as far as the speed disc allows (or the
    // whole missing separation), straight away from them, then kept in the cell.
    const double l = away.norm();
    const Vec2 dir = l > 0.0 ? Vec2(away / l) : Vec2(-out.cell.front().n);
    goal = x + (out.max_step > 0.0 ? out.max_step : d - nearest_broken) * dir;
    state.held = 0;
  } else if (out.inside_zones > 0 && exit.norm() > 0.0) {
    // Inside a zone (set over the agent): out by the shortest way, a whole step at a time (or at once
    // without a speed limit), whatever the law asks.
    double deepest = 0.0;
    for (const ConvexZone& z : zones)
      if (inside(z, x)) deepest = std::max(deepest, z.circle ? z.radius - (x - z.centre).norm() : out.max_step);
    goal = x + (out.max_step > 0.0 ? out.max_step : deepest + 1e-9) * Vec2(exit / exit.norm());
    state.held = 0;
  } else if (state.sidestep_left > 0) {
    goal = x + turn_right(step, p.sidestep_deg);
    out.sidestep = true;
    --state.sidestep_left;
  }
  out.x = solve(goal);
  if (out.broken == 0 && out.inside_zones == 0 && !out.sidestep) {
    out.held = len > p.stuck_min_step && (out.x - x).norm() < p.stuck_fraction * len;
    state.held = out.held ? state.held + 1 : 0;
    if (state.held >= p.stuck_steps && p.stuck_steps > 0) {
      state.held = 0;
      state.sidestep_left = p.stuck_steps - 1;  // this step is the first
      out.sidestep = out.sidestep_started = true;
      out.x = solve(x + turn_right(step, p.sidestep_deg));
    }
  }
  out.intervened = !(out.x == wanted);
  // The constraint with the least slack at the answer, when it binds there.
  double least = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < out.cell.size(); ++k) {
    const double slack = out.cell[k].b - out.cell[k].n.dot(out.x);
    if (slack <= 1e-9 * (1.0 + std::abs(out.cell[k].b)) && slack < least) {
      least = slack;
      const bool wall = source[k] == std::numeric_limits<std::int64_t>::min();
      out.blocking_id = source[k] >= 0 ? static_cast<std::int32_t>(source[k]) : -1;
      out.blocking_zone = source[k] >= 0 || wall ? -1 : static_cast<int>(-1 - source[k]);
    }
  }
  return out;
}

StepResult drive_safely(const VehicleParams& p, VehicleState& s, const StepResult& law,
                        const SafetyOutcome& f, double dt, double workspace, bool& outside) {
  outside = false;
  const Vec2 x = s.x;
  const auto command = [&](const Vec2& point) { return StepResult{point, (point - x) / dt, law.clamped}; };
  VehicleState trial = s;
  StepResult r = drive(p, trial, command(f.x), dt, workspace);
  if (f.braking && p.model == VehicleModel::DoubleIntegrator) {
    const double h = dt * p.seconds_per_model_time;
    const auto stop_of = [&](const VehicleState& v) { return Vec2(v.x + braking_displacement(v.velocity, p.max_accel, h)); };
    if (f.holds(r.x, stop_of(trial))) {
      s = trial;
      return r;
    }
    // The safe velocity nearest `toward` (the one toward f.x): first the last that keeps the cell on the
    // way from braking (which always does) to it, then a few rounds of a pattern search about that one
    // (rays at +-30, 60 and 85 degrees off the way to `toward`), each ray by bisection.
    const Vec2 toward = trial.velocity;
    const Vec2 v0 = s.velocity;
    const double reach = p.max_accel > 0.0 ? p.max_accel * h : std::numeric_limits<double>::infinity();
    const double fast = p.max_speed > 0.0 ? p.max_speed : std::numeric_limits<double>::infinity();
    // Only the cell's lines within the vehicle's reach can bind: |x1 - x| <= h max_speed and the new
    // braking displacement is at most the longest, so the search checks those alone.
    thread_local SafetyOutcome near;
    near = f;  // (the copy reuses the thread's storage)
    near.cell.clear();
    const double far = h * fast + braking_distance(fast, p.max_accel, h);
    for (const HalfPlane& c : f.cell)
      if (!(c.b - c.n.dot(x) > far * (1.0 + 1e-9) + tol(c.b))) near.cell.push_back(c);
    const auto safe = [&](const Vec2& v1) {
      if ((v1 - v0).norm() > reach * (1.0 + 1e-12) || v1.norm() > fast * (1.0 + 1e-12)) return false;
      const Vec2 x1 = x + (0.5 * h) * (v0 + v1);
      return near.holds(x1, x1 + braking_displacement(v1, p.max_accel, h));
    };
    // The farthest safe point from `from` (safe) along `way`, t in [0, 1].
    const auto along = [&](const Vec2& from, const Vec2& way) {
      if (safe(from + way)) return 1.0;
      double lo = 0.0, hi = 1.0;
      for (int k = 0; k < 20; ++k) {
        const double mid = 0.5 * (lo + hi);
        (safe(from + mid * way) ? lo : hi) = mid;
      }
      return lo;
    };
    const Vec2 brake = braking_velocity(v0, p.max_accel, h);
    Vec2 v = brake + along(brake, toward - brake) * (toward - brake);
    for (int round = 0; round < 4; ++round) {
      const Vec2 g = toward - v;
      if (g.norm() <= 1e-12 * (1.0 + toward.norm())) break;
      Vec2 best = v;
      for (const double deg : {30.0, -30.0, 60.0, -60.0, 85.0, -85.0}) {
        const Vec2 way = std::cos(deg * kPi / 180.0) * turn_right(g, deg);  // to the foot of toward on the ray
        const Vec2 c = v + along(v, way) * way;
        if ((c - toward).norm() < (best - toward).norm()) best = c;
      }
      if (best == v) break;
      v = best;
    }
    const auto with = [&](const Vec2& v1, VehicleState& st) {
      st = s;
      return drive(p, st, command(Vec2(x + h * v1)), dt, workspace);
    };
    r = with(v, trial);
    // drive's rounding (or the workspace's edge) can leave the cell by an ulp: then brake.
    if (!f.holds(r.x, stop_of(trial))) r = with(brake, trial);
    outside = !f.holds(r.x, stop_of(trial));
    s = trial;
    return r;
  }
  if (moves_as_law(p) || f.in_cell(r.x)) {
    s = trial;
    return r;
  }
  // The vehicle would leave the cell: look for a command that lands it inside.
  const double h = dt * p.seconds_per_model_time;
  const auto violation = [&f](const Vec2& q) {
    double v = f.max_step > 0.0 ? std::max(0.0, (q - f.from).norm() - f.max_step) : 0.0;
    for (const HalfPlane& c : f.cell) v = std::max(v, c.n.dot(q) - c.b);
    return v;
  };
  VehicleState best_state = trial;
  StepResult best = r;
  double best_v = violation(r.x);
  for (int k = 0; k <= 8; ++k) {
    const Vec2 aim = k == 8 ? x : Vec2(x + std::ldexp(1.0, -k) * (f.x - x));
    // A double integrator lands at x + h (v0 + v1) / 2: command v1 = 2 (aim - x) / h - v0.
    const Vec2 point =
        p.model == VehicleModel::DoubleIntegrator ? Vec2(x + 2.0 * (aim - x) - h * s.velocity) : aim;
    trial = s;
    r = drive(p, trial, command(point), dt, workspace);
    const double v = violation(r.x);
    if (f.in_cell(r.x)) {
      s = trial;
      return r;
    }
    if (v < best_v) best_v = v, best = r, best_state = trial;
  }
  outside = true;
  s = best_state;
  return best;
}

}  // namespace shapeform::core
