#include "metrics.hpp"

#include <algorithm>
#include <cmath>
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

int count_clusters(const std::vector<Vec2>& x, double link) {
  const int n = static_cast<int>(x.size());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  int clusters = n;
  const double link2 = link * link;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if ((x[i] - x[j]).squaredNorm() <= link2) {
        const int a = find(i), b = find(j);
        if (a != b) {
          parent[a] = b;
          --clusters;
        }
      }
  return clusters;
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

  m.clusters = count_clusters(x);
  std::vector<double> nn(n, std::numeric_limits<double>::infinity());
  double min_d = std::numeric_limits<double>::infinity(), max_d = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      const double d = (x[i] - x[j]).norm();
      nn[i] = std::min(nn[i], d);
      nn[j] = std::min(nn[j], d);
      min_d = std::min(min_d, d);
      max_d = std::max(max_d, d);
    }
  m.nn_cv = coefficient_of_variation(nn);
  m.min_separation = min_d;
  m.extent = max_d;
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
  const bool steady = hi - lo <= std::max(p_.band_abs, p_.band_rel * mean);
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
