#include "curve.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <deque>
#include <cmath>
#include <numeric>
#include <unordered_map>

namespace shapeform::core {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2.0 * kPi;
constexpr int kSamples = 4096;  ///< vertices of sampled curves: sagitta ~1e-6 of the size

Vec2 unit_or_x(const Vec2& y) {
  const double n = std::hypot(y.x(), y.y());
  return (n > 0.0 && std::isfinite(n)) ? Vec2(y / n) : Vec2(1.0, 0.0);
}

double wrap_angle(double a) {  // [0, 2 pi)
  a = std::fmod(a, kTwoPi);
  return a < 0 ? a + kTwoPi : a;
}

}  // namespace

// ------------------------------------------------------------------------------------------------
// Polyline

Polyline::Polyline(std::vector<Vec2> pts, bool closed) : closed_(closed) {
  for (const Vec2& p : pts)
    if (!std::isfinite(p.x()) || !std::isfinite(p.y())) throw ShapeError("curve has a non-finite point");
  // Drop repeated consecutive vertices (and a closing duplicate of the first).
  for (const Vec2& p : pts)
    if (pts_.empty() || (p - pts_.back()).norm() > 0.0) pts_.push_back(p);
  if (closed_ && pts_.size() > 1 && (pts_.front() - pts_.back()).norm() == 0.0) pts_.pop_back();
  if (pts_.size() < 2) throw ShapeError("curve has fewer than 2 distinct points");
  const std::size_t segs = closed_ ? pts_.size() : pts_.size() - 1;
  cum_.assign(segs + 1, 0.0);
  for (std::size_t k = 0; k < segs; ++k) cum_[k + 1] = cum_[k] + (pts_[(k + 1) % pts_.size()] - pts_[k]).norm();
  length_ = cum_.back();
  if (!(length_ > 0.0)) throw ShapeError("curve has zero length");
  for (const Vec2& p : pts_) radius_ = std::max(radius_, p.norm());
  const auto stride = std::max<std::size_t>(1, static_cast<std::size_t>(std::sqrt(static_cast<double>(segs))));
  for (std::size_t first = 0; first < segs; first += stride) {
    Chunk c{first, std::min(segs, first + stride), pts_[first], pts_[first]};
    for (std::size_t k = first; k <= c.last; ++k) {
      const Vec2& p = pts_[k % pts_.size()];
      c.lo = c.lo.cwiseMin(p);
      c.hi = c.hi.cwiseMax(p);
    }
    chunks_.push_back(c);
  }
}

Projection Polyline::on_segment(std::size_t k, const Vec2& y) const {
  const Vec2& a = pts_[k];
  const Vec2& b = pts_[(k + 1) % pts_.size()];
  const Vec2 d = b - a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? std::clamp((y - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  Projection p;
  p.point = a + t * d;
  p.s = cum_[k] + t * (cum_[k + 1] - cum_[k]);
  p.tangent = len2 > 0 ? Vec2(d / std::sqrt(len2)) : Vec2(1, 0);
  p.distance = (y - p.point).norm();
  return p;
}

Projection Polyline::closest(const Vec2& y) const {
  thread_local std::vector<std::pair<double, std::size_t>> order;  // reused: no allocation per call
  order.clear();
  for (std::size_t k = 0; k < chunks_.size(); ++k) {
    const Chunk& c = chunks_[k];
    const double dx = std::max({c.lo.x() - y.x(), 0.0, y.x() - c.hi.x()});
    const double dy = std::max({c.lo.y() - y.y(), 0.0, y.y() - c.hi.y()});
    order.emplace_back(dx * dx + dy * dy, k);
  }
  std::sort(order.begin(), order.end());
  Projection best;
  best.distance = std::numeric_limits<double>::infinity();
  for (const auto& [d2, k] : order) {
    if (d2 > best.distance * best.distance) break;
    for (std::size_t seg = chunks_[k].first; seg < chunks_[k].last; ++seg) {
      const Projection p = on_segment(seg, y);
      if (p.distance < best.distance) best = p;
    }
  }
  return best;
}

Vec2 Polyline::at(double s) const {
  if (closed_) {
    s = std::fmod(s, length_);
    if (s < 0) s += length_;
  } else {
    s = std::clamp(s, 0.0, length_);
  }
  const auto it = std::upper_bound(cum_.begin(), cum_.end(), s);
  std::size_t k = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, (it - cum_.begin()) - 1));
  k = std::min(k, cum_.size() - 2);
  const double seg = cum_[k + 1] - cum_[k];
  const double t = seg > 0 ? (s - cum_[k]) / seg : 0.0;
  return pts_[k] + t * (pts_[(k + 1) % pts_.size()] - pts_[k]);
}

// ------------------------------------------------------------------------------------------------
// Curves

namespace {

class LineCurve final : public Curve {
 public:
  LineCurve(double m, double c) : m_(m), c_(c), dir_(Vec2(1, m).normalized()) { foot_ = project(Vec2::Zero()); }
  Vec2 target(const Vec2& y) const override { return project(y); }
  Projection closest(const Vec2& y) const override {
    Projection p;
    p.point = project(y);
    p.s = (p.point - foot_).dot(dir_);
    p.tangent = dir_;
    p.distance = (y - p.point).norm();
    return p;
  }
  double length() const override { return std::numeric_limits<double>::infinity(); }
  bool closed() const override { return false; }
  Vec2 at(double s) const override { return foot_ + s * dir_; }
  double size() const override { return 1.0; }

 private:
  // Orthogonal projection onto x2 = m x1 + c (the paper prints "+mc" where "+c" is right).
  Vec2 project(const Vec2& y) const {
    const double t1 = (y.x() + m_ * y.y() - m_ * c_) / (1.0 + m_ * m_);
    return Vec2(t1, m_ * t1 + c_);
  }
  double m_, c_;
  Vec2 dir_, foot_;
};

class CircleCurve final : public Curve {
 public:
  explicit CircleCurve(double r0) : r0_(r0) {}
  Vec2 target(const Vec2& y) const override { return r0_ * unit_or_x(y); }
  Projection closest(const Vec2& y) const override {
    const Vec2 u = unit_or_x(y);
    Projection p;
    p.point = r0_ * u;
    p.s = r0_ * wrap_angle(std::atan2(u.y(), u.x()));
    p.tangent = Vec2(-u.y(), u.x());
    p.distance = (y - p.point).norm();
    return p;
  }
  double length() const override { return kTwoPi * r0_; }
  bool closed() const override { return true; }
  Vec2 at(double s) const override { return r0_ * Vec2(std::cos(s / r0_), std::sin(s / r0_)); }
  double size() const override { return r0_; }

 private:
  double r0_;
};

/// A curve whose closest points, arc lengths and points come from a polyline; the target is given.
class SampledCurve : public Curve {
 public:
  SampledCurve(Polyline poly, double size) : poly_(std::move(poly)), size_(size) {}
  Projection closest(const Vec2& y) const override { return poly_.closest(y); }
  double length() const override { return poly_.length(); }
  bool closed() const override { return poly_.closed(); }
  Vec2 at(double s) const override { return poly_.at(s); }
  double size() const override { return size_; }
  Vec2 target(const Vec2& y) const override { return poly_.closest(y).point; }

 protected:
  Polyline poly_;
  double size_;
};

class EllipseCurve final : public SampledCurve {
 public:
  EllipseCurve(double a, double b) : SampledCurve(sample(a, b), std::max(a, b)), a_(a), b_(b) {}
  Vec2 target(const Vec2& y) const override {
    // Radial projection as the paper defines it: theta = atan2(a y2, b y1); (a, 0) at the centre.
    const double th = std::atan2(a_ * y.y(), b_ * y.x());
    return Vec2(a_ * std::cos(th), b_ * std::sin(th));
  }

 private:
  static Polyline sample(double a, double b) {
    std::vector<Vec2> p(kSamples);
    for (int k = 0; k < kSamples; ++k) {
      const double th = kTwoPi * k / kSamples;
      p[k] = Vec2(a * std::cos(th), b * std::sin(th));
    }
    return Polyline(std::move(p), true);
  }
  double a_, b_;
};

class SquareCurve final : public SampledCurve {
 public:
  explicit SquareCurve(double a)
      : SampledCurve(Polyline({Vec2(a, 0), Vec2(a, a), Vec2(-a, a), Vec2(-a, -a), Vec2(a, -a)}, true), a), a_(a) {}
  Vec2 target(const Vec2& y) const override {
    const double m = std::max(std::abs(y.x()), std::abs(y.y()));
    if (!(m > 0.0) || !std::isfinite(m)) return Vec2(a_, 0.0);
    return (a_ / m) * y;
  }

 private:
  double a_;
};

class PolarCurve final : public SampledCurve {
 public:
  explicit PolarCurve(std::vector<double> r) : SampledCurve(sample(r), *std::max_element(r.begin(), r.end())), r_(std::move(r)) {}
  Vec2 target(const Vec2& y) const override {
    const Vec2 u = unit_or_x(y);
    const double phi = wrap_angle(std::atan2(u.y(), u.x()));
    const double k = phi / kTwoPi * static_cast<double>(r_.size());
    const auto k0 = static_cast<std::size_t>(k) % r_.size();
    const double t = k - std::floor(k);
    return ((1 - t) * r_[k0] + t * r_[(k0 + 1) % r_.size()]) * u;
  }

 private:
  static Polyline sample(const std::vector<double>& r) {
    std::vector<Vec2> p(r.size());
    for (std::size_t k = 0; k < r.size(); ++k) {
      const double phi = kTwoPi * static_cast<double>(k) / static_cast<double>(r.size());
      p[k] = r[k] * Vec2(std::cos(phi), std::sin(phi));
    }
    return Polyline(std::move(p), true);
  }
  std::vector<double> r_;
};

double polyline_size(const Polyline& p) {
  Vec2 lo = p.points().front(), hi = lo;
  for (const Vec2& v : p.points()) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  return std::max(0.5 * (hi - lo).norm(), 1e-9);
}

/// Newton steps along the gradient toward f = 0 from y. False when the gradient vanishes, a value is
/// not finite, or it does not converge.
bool newton_project(const std::function<double(double, double)>& f, const Vec2& y, double tol, Vec2& out) {
  Vec2 x = y;
  for (int it = 0; it < 30; ++it) {
    const double h = 1e-6 * (1.0 + x.norm());
    const double fx = f(x.x(), x.y());
    const Vec2 g((f(x.x() + h, x.y()) - f(x.x() - h, x.y())) / (2 * h),
                 (f(x.x(), x.y() + h) - f(x.x(), x.y() - h)) / (2 * h));
    const double g2 = g.squaredNorm();
    if (!std::isfinite(fx) || !std::isfinite(g2) || g2 < 1e-24) return false;
    const Vec2 step = (fx / g2) * g;
    x -= step;
    if (step.norm() <= tol) {
      out = x;
      return std::isfinite(x.norm());
    }
  }
  return false;
}

class ImplicitCurve final : public SampledCurve {
 public:
  ImplicitCurve(std::function<double(double, double)> f, Polyline contour)
      : SampledCurve(std::move(contour), 0.0), f_(std::move(f)) {
    size_ = polyline_size(poly_);
  }
  Vec2 target(const Vec2& y) const override {
    // Newton steps along the gradient: y <- y - f grad f / |grad f|^2 (the paper's Cartesian equation).
    // Accepted only when they converge to a zero near the query (not a far branch reached by a wild
    // step); otherwise, and where the gradient vanishes, the closest point of the traced contour.
    const Projection c = poly_.closest(y);
    Vec2 x;
    if (newton_project(f_, y, 1e-12 * (1.0 + size_), x) && (x - y).norm() <= 2.0 * c.distance + 1e-3 * size_) return x;
    return c.point;
  }

 private:
  std::function<double(double, double)> f_;
};

/// Marching squares: the longest traced component of f = 0 over the box.
Polyline trace_contour(const std::function<double(double, double)>& f, double half_box, int grid) {
  const int n = grid + 1;
  const double h = 2.0 * half_box / grid;
  std::vector<double> v(static_cast<std::size_t>(n) * n);
  const auto node = [&](int i, int j) { return Vec2(-half_box + i * h, -half_box + j * h); };
  const auto val = [&](int i, int j) -> double& { return v[static_cast<std::size_t>(j) * n + i]; };
  bool any_finite = false;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Vec2 p = node(i, j);
      double fv = f(p.x(), p.y());
      if (fv == 0.0) fv = 1e-300;  // keep signs strict
      val(i, j) = fv;
      any_finite = any_finite || std::isfinite(fv);
    }
  if (!any_finite) throw ShapeError("implicit curve: f is not finite anywhere in the box");
  // Edge ids: 2*(j*n + i) for the edge (i,j)-(i+1,j), +1 for (i,j)-(i,j+1).
  const auto hedge = [&](int i, int j) { return 2L * (static_cast<long>(j) * n + i); };
  const auto vedge = [&](int i, int j) { return 2L * (static_cast<long>(j) * n + i) + 1; };
  std::unordered_map<long, Vec2> crossing;
  const auto cross = [&](long id, int i0, int j0, int i1, int j1) {
    if (crossing.count(id)) return;
    const double a = val(i0, j0), b = val(i1, j1);
    const double t = a / (a - b);
    crossing[id] = node(i0, j0) + t * (node(i1, j1) - node(i0, j0));
  };
  std::vector<std::pair<long, long>> segs;
  for (int j = 0; j < grid; ++j)
    for (int i = 0; i < grid; ++i) {
      const double c[4] = {val(i, j), val(i + 1, j), val(i + 1, j + 1), val(i, j + 1)};
      if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2]) || !std::isfinite(c[3])) continue;
      // Edges: 0 bottom, 1 right, 2 top, 3 left.
      const long e[4] = {hedge(i, j), vedge(i + 1, j), hedge(i, j + 1), vedge(i, j)};
      const int ends[4][4] = {{i, j, i + 1, j}, {i + 1, j, i + 1, j + 1}, {i, j + 1, i + 1, j + 1}, {i, j, i, j + 1}};
      std::vector<int> hit;
      for (int k = 0; k < 4; ++k)
        if ((c[k] > 0) != (c[(k + 1) % 4] > 0)) hit.push_back(k);
      for (int k : hit) cross(e[k], ends[k][0], ends[k][1], ends[k][2], ends[k][3]);
      if (hit.size() == 2) {
        segs.emplace_back(e[hit[0]], e[hit[1]]);
      } else if (hit.size() == 4) {  // saddle: decide by the centre value
        const bool centre_pos = (c[0] + c[1] + c[2] + c[3]) > 0;
        if (centre_pos == (c[0] > 0)) {
          segs.emplace_back(e[0], e[1]);
          segs.emplace_back(e[2], e[3]);
        } else {
          segs.emplace_back(e[0], e[3]);
          segs.emplace_back(e[1], e[2]);
        }
      }
    }
  if (segs.empty()) throw ShapeError("implicit curve: f(x, y) = 0 has no real points in the box");
  // Link segments into chains through shared edge crossings.
  std::unordered_map<long, std::vector<std::size_t>> at_edge;
  for (std::size_t k = 0; k < segs.size(); ++k) {
    at_edge[segs[k].first].push_back(k);
    at_edge[segs[k].second].push_back(k);
  }
  std::vector<char> used(segs.size(), 0);
  int pieces = 0;
  std::vector<Vec2> best;
  bool best_closed = false;
  double best_len = -1.0;
  for (std::size_t s0 = 0; s0 < segs.size(); ++s0) {
    if (used[s0]) continue;
    // A zero set in many pieces is a pattern, not a curve a formation can follow (agents would settle
    // on whichever piece is nearest, all over the box); tracing it would also cost without bound.
    if (++pieces > kImplicitPiecesMax)
      throw ShapeError("implicit curve: f(x, y) = 0 falls into more than " + std::to_string(kImplicitPiecesMax) +
                       " separate pieces in the box (a pattern, or a curve finer than the tracing grid)");
    used[s0] = 1;
    std::deque<long> chain = {segs[s0].first, segs[s0].second};
    // Grow at the back, then at the front.
    for (int side = 0; side < 2; ++side) {
      while (true) {
        const long end = side == 0 ? chain.back() : chain.front();
        std::size_t next = segs.size();
        for (std::size_t k : at_edge[end])
          if (!used[k]) next = k;
        if (next == segs.size()) break;
        used[next] = 1;
        const long other = segs[next].first == end ? segs[next].second : segs[next].first;
        if (side == 0) chain.push_back(other);
        else chain.push_front(other);
      }
    }
    const bool closed = chain.size() > 3 && chain.front() == chain.back();
    if (closed) chain.pop_back();
    std::vector<Vec2> pts;
    for (long id : chain) pts.push_back(crossing[id]);
    double len = 0;
    for (std::size_t k = 1; k < pts.size(); ++k) len += (pts[k] - pts[k - 1]).norm();
    if (len > best_len) {
      best_len = len;
      best = std::move(pts);
      best_closed = closed;
    }
  }
  return Polyline(std::move(best), best_closed);
}

}  // namespace

std::shared_ptr<const Curve> make_line(double m, double c) {
  if (!std::isfinite(m) || !std::isfinite(c)) throw ShapeError("line: m and c must be finite");
  return std::make_shared<LineCurve>(m, c);
}
std::shared_ptr<const Curve> make_circle(double r0) {
  if (!(r0 > 0) || !std::isfinite(r0)) throw ShapeError("circle: r0 must be > 0");
  return std::make_shared<CircleCurve>(r0);
}
std::shared_ptr<const Curve> make_ellipse(double a, double b) {
  if (!(a > 0) || !(b > 0) || !std::isfinite(a) || !std::isfinite(b)) throw ShapeError("ellipse: a and b must be > 0");
  return std::make_shared<EllipseCurve>(a, b);
}
std::shared_ptr<const Curve> make_square(double a) {
  if (!(a > 0) || !std::isfinite(a)) throw ShapeError("square: a must be > 0");
  return std::make_shared<SquareCurve>(a);
}
std::shared_ptr<const Curve> make_polygon(std::vector<Vec2> vertices, bool closed) {
  const std::size_t need = closed ? 3 : 2;
  if (vertices.size() < need)
    throw ShapeError(std::string("polygon: ") + (closed ? "a closed" : "an open") + " polygon needs at least " +
                     std::to_string(need) + " vertices, got " + std::to_string(vertices.size()));
  for (std::size_t k = 0; k + 1 < vertices.size() + (closed ? 1 : 0); ++k)
    if ((vertices[(k + 1) % vertices.size()] - vertices[k]).norm() == 0.0)
      throw ShapeError("polygon: vertices " + std::to_string(k) + " and " + std::to_string((k + 1) % vertices.size()) +
                       " coincide (zero-length edge)");
  Polyline p(std::move(vertices), closed);
  const double size = polyline_size(p);
  if (closed) {  // all vertices on one line: zero area
    const auto& v = p.points();
    double area2 = 0;
    for (std::size_t k = 0; k < v.size(); ++k) {
      const Vec2& a = v[k];
      const Vec2& b = v[(k + 1) % v.size()];
      area2 += a.x() * b.y() - b.x() * a.y();
    }
    if (std::abs(area2) <= 1e-12 * size * size) throw ShapeError("polygon: the vertices are collinear (zero area)");
  }
  return std::make_shared<SampledCurve>(std::move(p), size);
}
std::shared_ptr<const Curve> make_polar(std::vector<double> r) {
  if (r.size() < 16) throw ShapeError("polar: too few samples");
  for (std::size_t k = 0; k < r.size(); ++k)
    if (!(r[k] > 0) || !std::isfinite(r[k])) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "polar: r(phi) must be finite and > 0 for every phi, got r(%.4g) = %.6g",
                    kTwoPi * static_cast<double>(k) / static_cast<double>(r.size()), r[k]);
      throw ShapeError(buf);
    }
  return std::make_shared<PolarCurve>(std::move(r));
}
std::shared_ptr<const Curve> make_sampled(std::vector<Vec2> points, bool closed) {
  Polyline p(std::move(points), closed);
  const double size = polyline_size(p);
  return std::make_shared<SampledCurve>(std::move(p), size);
}
std::shared_ptr<const Curve> make_implicit(std::function<double(double, double)> f, double half_box, int grid) {
  if (!(half_box > 0) || grid < 8) throw ShapeError("implicit: bad tracing box");
  const Polyline traced = trace_contour(f, half_box, grid);
  // Marching squares is only accurate to a fraction of a cell: resample the contour finely by arc
  // length and move every sample onto f = 0 with Newton steps.
  const int n = traced.closed() ? kSamples : kSamples + 1;
  std::vector<Vec2> pts(static_cast<std::size_t>(n));
  const double step = traced.length() / (traced.closed() ? n : n - 1);
  for (int k = 0; k < n; ++k) {
    const Vec2 p = traced.at(k * step);
    Vec2 q;
    pts[static_cast<std::size_t>(k)] = newton_project(f, p, 1e-13 * (1.0 + p.norm()), q) && (q - p).norm() < 2.0 * step + 2.0 * half_box / grid ? q : p;
  }
  return std::make_shared<ImplicitCurve>(std::move(f), Polyline(std::move(pts), traced.closed()));
}

}  // namespace shapeform::core
