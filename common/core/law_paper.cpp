#include "law_paper.hpp"

#include <cmath>

namespace shapeform::core {

namespace {
/// (sigma^2 + d^2)^-beta: the paper's foraging kernel.
inline double kernel(double d2, const Gains& g) {
  return std::pow(g.sigma * g.sigma + d2, -g.beta);
}
constexpr double kGoldenAngle = 2.39996322972865332223;  // pi (3 - sqrt 5)
}  // namespace

Vec2 cohesion_term(const Vec2& xi, const std::vector<Neighbour>& nbrs, const Gains& g) {
  Vec2 sum = Vec2::Zero();
  for (const Neighbour& n : nbrs) {
    const Vec2 d = n.x - xi;
    sum += kernel(d.squaredNorm(), g) * d;
  }
  return g.k1 * sum;
}

Vec2 attraction_term(const Vec2& xi, const Vec2& xt, const Gains& g) {
  const Vec2 d = xt - xi;
  return g.k2 * kernel(d.squaredNorm(), g) * d;
}

int nearest_neighbour(const Vec2& xi, const std::vector<Neighbour>& nbrs) {
  int best = -1;
  double best_d2 = 0.0;
  for (int k = 0; k < static_cast<int>(nbrs.size()); ++k) {
    const double d2 = (nbrs[k].x - xi).squaredNorm();
    if (best < 0 || d2 < best_d2 || (d2 == best_d2 && nbrs[k].id < nbrs[best].id)) {
      best = k;
      best_d2 = d2;
    }
  }
  return best;
}

Vec2 escape_direction(std::int32_t id) {
  const double ang = kGoldenAngle * static_cast<double>(id);
  return Vec2(std::cos(ang), std::sin(ang));
}

Vec2 repulsion_term(std::int32_t self_id, const Vec2& xi, const std::vector<Neighbour>& nbrs,
                    const Gains& g) {
  const int n = nearest_neighbour(xi, nbrs);
  if (n < 0 || g.r == 0.0) return Vec2::Zero();
  return repulsion_from(self_id, xi, nbrs[n].x, g);
}

Vec2 repulsion_from(std::int32_t self_id, const Vec2& xi, const Vec2& xn, const Gains& g) {
  const Vec2 d = xi - xn;
  const double len = std::hypot(d.x(), d.y());
  if (len > 0.0 && std::isfinite(len)) return (g.r / len) * d;
  return g.r * escape_direction(self_id);
}

Vec2 paper_velocity(std::int32_t self_id, const Vec2& xi, const std::vector<Neighbour>& nbrs,
                    const Vec2& xt, const Gains& g) {
  return cohesion_term(xi, nbrs, g) + attraction_term(xi, xt, g) +
         repulsion_term(self_id, xi, nbrs, g);
}

}  // namespace shapeform::core
