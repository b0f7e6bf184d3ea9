#include "metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <utility>

namespace shapeform::core {

std::optional<double> coefficient_of_variation(const std::vector<double>& v) {
  if (v.empty()) return std::nullopt;  // one gap (two agents on an open curve) is trivially even: 0
  const double n = static_cast<double>(v.size());
  const double mean = std::accumulate(v.begin(), v.end(), 0.0) / n;
  // A mean this small means every value is zero up to rounding (e.g. all agents on one point).
  if (!(mean > 1e-12)) return std::nullopt;
  double ss = 0.0;
  for (double x : v) ss += (x - mean) * (x - mean);
  return std::sqrt(ss / n) / mean;
}

namespace {
bool angle_ordered(ShapeKind k) {
  return k == ShapeKind::Circle || k == ShapeKind::Ellipse || k == ShapeKind::Square || k == ShapeKind::Polar;
}

/// Agents' indices ordered by the arc length of their closest points, with those arc lengths.
std::vector<std::pair<double, std::size_t>> arc_order(const ShapeSpec& shape, const Curve& curve,
                                                      const std::vector<Vec2>& x) {
  std::vector<std::pair<double, std::size_t>> order(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) order[i] = {closest_point(shape, curve, x[i]).s, i};
  std::sort(order.begin(), order.end());
  return order;
}
}  // namespace

std::vector<double> consecutive_gaps(const ShapeSpec& shape, const Curve& curve, const std::vector<Vec2>& x) {
  const std::size_t n = x.size();
  std::vector<double> gaps;
  if (n < 2) return gaps;
  std::vector<std::pair<double, std::size_t>> order(n);
  if (angle_ordered(shape.kind)) {
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2 y = x[i] - shape.centre;
      order[i] = {std::atan2(y.y(), y.x()), i};
    }
    std::sort(order.begin(), order.end());
  } else {
    order = arc_order(shape, curve, x);
  }
  gaps.reserve(n);
  for (std::size_t k = 0; k + 1 < n; ++k) gaps.push_back((x[order[k + 1].second] - x[order[k].second]).norm());
  if (curve.closed()) gaps.push_back((x[order.front().second] - x[order.back().second]).norm());
  return gaps;
}

std::vector<double> arc_gaps(const ShapeSpec& shape, const Curve& curve, const std::vector<Vec2>& x) {
  std::vector<double> gaps;
  if (x.size() < 2) return gaps;
  const auto order = arc_order(shape, curve, x);
  for (std::size_t k = 0; k + 1 < order.size(); ++k) gaps.push_back(order[k + 1].first - order[k].first);
  if (curve.closed()) gaps.push_back(shape.scale * curve.length() - (order.back().first - order.front().first));
  return gaps;
}

namespace {
/// Points binned on a uniform grid of square cells over their bounding box (a counting sort: the
/// indices of cell c are order[start[c]] .. order[start[c + 1] - 1]). The cell side is chosen so that
/// a spread-out swarm has about one point per cell, and never below `min_cell`.
class Grid {
 public:
  Grid(const std::vector<Vec2>& x, double min_cell) {
    Vec2 hi = x.front();
    lo_ = hi;
    for (const Vec2& v : x) {
      lo_ = lo_.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    const Vec2 size = hi - lo_;
    const double n = static_cast<double>(x.size());
    // About one point per cell over the box's area, at most 4N cells a side (a flat box: agents on a
    // line), so that the grid has at most about 9N cells.
    cell_ = std::max({std::sqrt(size.x() * size.y() / n), size.x() / (4.0 * n), size.y() / (4.0 * n), min_cell,
                      1e-300});
    cols_ = static_cast<int>(std::min(size.x() / cell_, 4.0 * n)) + 1;
    rows_ = static_cast<int>(std::min(size.y() / cell_, 4.0 * n)) + 1;
    start_.assign(static_cast<std::size_t>(cols_) * static_cast<std::size_t>(rows_) + 1, 0);
    std::vector<int> cell_of(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      cell_of[i] = index(col(x[i]), row(x[i]));
      ++start_[static_cast<std::size_t>(cell_of[i]) + 1];
    }
    std::partial_sum(start_.begin(), start_.end(), start_.begin());
    order_.resize(x.size());
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < x.size(); ++i)
      order_[static_cast<std::size_t>(fill[static_cast<std::size_t>(cell_of[i])]++)] = static_cast<int>(i);
  }

  double cell() const { return cell_; }
  int col(const Vec2& v) const { return place(v.x() - lo_.x(), cols_); }
  int row(const Vec2& v) const { return place(v.y() - lo_.y(), rows_); }
  /// Whether the cells at Chebyshev distance r from cell (c, r0) reach into the grid.
  bool ring_in_grid(int c, int r0, int r) const {
    return c - r >= 0 || c + r < cols_ || r0 - r >= 0 || r0 + r < rows_;
  }
  /// f(j) for every point j in the cells at Chebyshev distance exactly r from cell (c, r0).
  template <class F>
  void for_each_on_ring(int c, int r0, int r, F&& f) const {
    const auto visit = [&](int xc, int y) {
      if (xc < 0 || xc >= cols_ || y < 0 || y >= rows_) return;
      const auto k = static_cast<std::size_t>(index(xc, y));
      for (int s = start_[k]; s < start_[k + 1]; ++s) f(order_[static_cast<std::size_t>(s)]);
    };
    if (r == 0) return visit(c, r0);
    for (int xc = c - r; xc <= c + r; ++xc) {
      visit(xc, r0 - r);
      visit(xc, r0 + r);
    }
    for (int y = r0 - r + 1; y <= r0 + r - 1; ++y) {
      visit(c - r, y);
      visit(c + r, y);
    }
  }

 private:
  int index(int c, int r) const { return r * cols_ + c; }
  int place(double offset, int cells) const {
    return static_cast<int>(std::clamp(offset / cell_, 0.0, static_cast<double>(cells - 1)));
  }

  Vec2 lo_;
  double cell_ = 1.0;
  int cols_ = 1, rows_ = 1;
  std::vector<int> start_, order_;
};
}  // namespace

int count_clusters(const std::vector<Vec2>& x, double link) {
  const int n = static_cast<int>(x.size());
  if (n == 0) return 0;
  std::vector<int> parent(static_cast<std::size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  int clusters = n;
  const double link2 = link * link;
  // Every pair within `link` lies in neighbouring cells of a grid whose cells are at least `link` wide.
  const Grid grid(x, link);
  for (int i = 0; i < n; ++i) {
    const int c = grid.col(x[i]), r = grid.row(x[i]);
    for (int ring = 0; ring <= 1; ++ring)
      grid.for_each_on_ring(c, r, ring, [&](int j) {
        if (j <= i || (x[i] - x[j]).squaredNorm() > link2) return;
        const int a = find(i), b = find(j);
        if (a != b) {
          parent[a] = b;
          --clusters;
        }
      });
  }
  return clusters;
}

std::vector<double> nearest_squared(const std::vector<Vec2>& p, const std::vector<std::int32_t>& pid,
                                    const std::vector<Vec2>& q, const std::vector<std::int32_t>& qid) {
  std::vector<double> best(q.size(), std::numeric_limits<double>::infinity());
  if (p.empty() || q.empty()) return best;
  const Grid grid(p, 0.0);
  for (std::size_t k = 0; k < q.size(); ++k) {
    const Vec2& at = q[k];
    // A query outside the grid starts from the cell its projection onto the grid's box falls in: it is
    // at least as far from every cell as its projection is (the box is convex).
    const int c = grid.col(at), r = grid.row(at);
    double b = std::numeric_limits<double>::infinity();
    // A point in a cell beyond ring k is at least k cells away: once the best is within that (less a
    // margin far above the rounding of the cell's index), stop.
    for (int ring = 0; grid.ring_in_grid(c, r, ring); ++ring) {
      grid.for_each_on_ring(c, r, ring, [&](int j) {
        const auto i = static_cast<std::size_t>(j);
        if (pid[i] == qid[k]) return;  // the query's own point
        const double dx = p[i].x() - at.x(), dy = p[i].y() - at.y();
        const double d = dx * dx + dy * dy;
        b = d < b ? d : b;
      });
      const double reach = ring * grid.cell() * (1.0 - 1e-9);
      if (b <= reach * reach) break;
    }
    best[k] = b;
  }
  return best;
}

std::vector<double> nearest_distances(const std::vector<Vec2>& x) {
  std::vector<std::int32_t> ids(x.size());
  std::iota(ids.begin(), ids.end(), 0);
  std::vector<double> nn = nearest_squared(x, ids, x, ids);
  for (double& d : nn) d = std::sqrt(d);
  return nn;
}

double largest_distance(const std::vector<Vec2>& x) {
  if (x.size() < 2) return 0.0;
  // The convex hull (Andrew's monotone chain, counter-clockwise, collinear points dropped).
  std::vector<Vec2> p(x);
  std::sort(p.begin(), p.end(),
            [](const Vec2& a, const Vec2& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  const auto cross = [](const Vec2& o, const Vec2& a, const Vec2& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Vec2> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);  // the last point is the first
  const std::size_t m = h.size();
  if (m < 2) return 0.0;  // every agent on one point
  double best = 0.0;
  if (m <= 32) {
    for (std::size_t i = 0; i < m; ++i)
      for (std::size_t j = i + 1; j < m; ++j) best = std::max(best, (h[i] - h[j]).squaredNorm());
    return std::sqrt(best);
  }
  // Rotating calipers: for each hull edge (i, i + 1) the vertex j farthest from its line, which moves
  // forward as i does; the diameter is between an edge's end and such a vertex. Its neighbours are
  // checked too, so that a tie decided by rounding cannot skip the farthest pair.
  std::size_t j = 1;
  for (std::size_t i = 0; i < m; ++i) {
    const std::size_t ni = (i + 1) % m;
    for (std::size_t steps = 0; steps < m && cross(h[i], h[ni], h[(j + 1) % m]) > cross(h[i], h[ni], h[j]); ++steps)
      j = (j + 1) % m;
    for (const std::size_t a : {i, ni})
      for (const std::size_t b : {(j + m - 1) % m, j, (j + 1) % m})
        best = std::max(best, (h[a] - h[b]).squaredNorm());
  }
  return std::sqrt(best);
}

Metrics compute_metrics(const CompiledCommand& cmd, const std::vector<Vec2>& x, double t, bool pairwise) {
  Metrics m;
  const std::size_t n = x.size();
  m.agents = static_cast<int>(n);
  if (n == 0) return m;
  const ShapeSpec s = shape_at(cmd, t);
  const Curve& curve = cmd.curve();
  double err_sum = 0.0, err_max = 0.0, cerr_sum = 0.0, cerr_max = 0.0;
  for (const Vec2& xi : x) {
    const double e = (xi - target_point(s, curve, xi)).norm();
    err_sum += e;
    err_max = std::max(err_max, e);
    const double ce = closest_point(s, curve, xi).distance;
    cerr_sum += ce;
    cerr_max = std::max(cerr_max, ce);
  }
  m.shape_error_mean = err_sum / static_cast<double>(n);
  m.shape_error_max = err_max;
  m.curve_error_mean = cerr_sum / static_cast<double>(n);
  m.curve_error_max = cerr_max;
  if (n == 1) m.clusters = 1;

  if (cmd.tracking.enabled) {
    const Vec2 c = s.centre;
    const double radius = s.scale * s.r0;  // the ring as drawn: r0 scaled about the centre
    Vec2 mean = Vec2::Zero();
    double ring = 0.0;
    for (const Vec2& xi : x) {
      mean += xi;
      ring += std::abs((xi - c).norm() - radius);
    }
    m.centroid_error = (mean / static_cast<double>(n) - c).norm();
    // A ring only around a tracked circle; another tracked shape has its shape error instead.
    if (s.kind == ShapeKind::Circle) m.ring_error = ring / static_cast<double>(n);
  }
  if (n < 2) return m;
  m.gap_cv = coefficient_of_variation(consecutive_gaps(s, curve, x));
  m.arc_gap_cv = coefficient_of_variation(arc_gaps(s, curve, x));
  if (!pairwise) return m;

  const std::vector<double> nn = nearest_distances(x);
  m.nn_cv = coefficient_of_variation(nn);
  m.min_separation = *std::min_element(nn.begin(), nn.end());
  // No two agents within the link (a spread-out swarm; the margin is far above the roundings of a
  // distance): every agent is its own cluster, without the linking pass.
  m.clusters = m.min_separation > kClusterLink * (1.0 + 1e-9) ? static_cast<int>(n) : count_clusters(x);
  m.extent = largest_distance(x);
  return m;
}

std::optional<int> settle_index(const std::vector<double>& shape_error,
                                const std::vector<std::optional<double>>& gap_cv,
                                const SettleParams& p) {
  const std::size_t n = std::min(shape_error.size(), gap_cv.size());
  if (n == 0) return std::nullopt;
  // The plateau is the median of the last tenth of the run (at least 10 samples), so that the
  // period-2 chatter of Euler dt = 1 does not make it depend on which phase the run ended on.
  const std::size_t tail = std::min(n, std::max<std::size_t>(10, n / 10));
  std::vector<double> last(shape_error.end() - static_cast<long>(tail), shape_error.begin() + static_cast<long>(n));
  std::nth_element(last.begin(), last.begin() + static_cast<long>(tail / 2), last.end());
  const double plateau = last[tail / 2];
  const double band = std::max(p.band_abs, p.band_rel * plateau);
  for (std::size_t k = n; k-- > 0;) {
    const bool ok = std::abs(shape_error[k] - plateau) <= band && gap_cv[k] && *gap_cv[k] <= p.gap_cv_max;
    if (!ok) {
      if (k + 1 == n) return std::nullopt;
      return static_cast<int>(k + 1);
    }
  }
  return 0;
}

double on_shape_bound(const CompiledCommand& cmd, const ConvergenceParams& p) {
  return std::max(p.on_shape_abs, p.on_shape_rel * cmd.shape.scale * cmd.curve().size());
}

std::optional<double> spread(const std::vector<Vec2>& x) {
  if (x.empty()) return std::nullopt;
  Vec2 lo = x.front(), hi = lo;
  for (const Vec2& v : x) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  return 0.5 * (hi - lo).norm();
}

const char* to_string(ConvergenceDetector::Why w) {
  switch (w) {
    case ConvergenceDetector::Why::Converged: return "converged";
    case ConvergenceDetector::Why::NoData: return "no data";
    case ConvergenceDetector::Why::OffShape: return "off the shape";
    case ConvergenceDetector::Why::Uneven: return "uneven";
    case ConvergenceDetector::Why::Unsteady: return "unsteady";
    case ConvergenceDetector::Why::Growing: return "growing";
    case ConvergenceDetector::Why::Holding: return "holding";
    case ConvergenceDetector::Why::Blocked: return "blocked";
  }
  return "?";
}

void ConvergenceDetector::set_command(const CompiledCommand& cmd) {
  on_shape_ = on_shape_bound(cmd, p_);
  reset();
}

void ConvergenceDetector::reset() {
  window_.clear();
  spreads_.clear();
  converged_ = false;
  why_ = Why::NoData;
}

void ConvergenceDetector::blocked() {
  reset();
  why_ = Why::Blocked;
}

void ConvergenceDetector::add(double t, const std::optional<double>& shape_error,
                              const std::optional<double>& gap_cv, const std::optional<double>& spread) {
  if (!shape_error || !gap_cv || *gap_cv > p_.gap_cv_max || !(*shape_error <= on_shape_)) {
    reset();
    why_ = !shape_error || !gap_cv ? Why::NoData : !(*shape_error <= on_shape_) ? Why::OffShape : Why::Uneven;
    return;
  }
  window_.push_back({t, *shape_error, *gap_cv});
  // Keep samples covering exactly the last `hold` of model time (plus the one just before it).
  while (window_.size() > 2 && window_[1].t <= t - p_.hold) window_.erase(window_.begin());
  double lo = window_.front().err, hi = lo, sum = 0.0;
  for (const Sample& s : window_) {
    lo = std::min(lo, s.err);
    hi = std::max(hi, s.err);
    sum += s.err;
  }
  const double mean = sum / static_cast<double>(window_.size());
  const double band = std::max(p_.band_abs, p_.band_rel * mean);
  // Steady until converged: the error stayed within the band over the span. Once converged, only a
  // rise by more than the band above the span's lowest error ends it: a formation still creeping
  // closer to its shape stays converged (otherwise a decay of about band / hold could flip the
  // verdict back and forth).
  const bool steady = converged_ ? window_.back().err - lo <= band : hi - lo <= band;
  // Growth over the last `hold` span, whatever restarted the window meanwhile, against the same
  // size-relative bound: on its shape a formation can only keep growing along an unbounded curve
  // (the line), where it never settles.
  bool growing = false;
  if (spread && on_shape_ < std::numeric_limits<double>::infinity()) {
    spreads_.push_back({t, *spread});
    while (spreads_.size() > 2 && spreads_[1].first <= t - p_.hold) spreads_.erase(spreads_.begin());
    double smallest = *spread;
    for (const auto& [ts, sp] : spreads_) smallest = std::min(smallest, sp);
    growing = *spread - smallest > on_shape_;
  }
  if (!steady || growing) {
    // Restart the window at the newest sample: the error or the extent is still moving.
    window_.erase(window_.begin(), window_.end() - 1);
    converged_ = false;
    why_ = !steady ? Why::Unsteady : Why::Growing;
    return;
  }
  converged_ = t - window_.front().t >= p_.hold;
  why_ = converged_ ? Why::Converged : Why::Holding;
}

}  // namespace shapeform::core
