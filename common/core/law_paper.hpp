#pragma once
/// The paper's control law (Goswami et al., eq. 2), term by term.
#include <vector>

#include "types.hpp"

namespace shapeform::core {

/// Gains of the paper's law. Paper values by default.
struct Gains {
  double k1 = 0.1;     ///< cohesion (foraging) gain
  double k2 = 2.0;     ///< attraction-to-shape gain
  double sigma = 3.5;  ///< softening length
  double beta = 1.2;   ///< decay exponent
  double r = 0.1;      ///< nearest-neighbour repulsion magnitude
};

/// sum_j k1 (x_j - x_i) / (sigma^2 + |x_j - x_i|^2)^beta over all neighbours.
Vec2 cohesion_term(const Vec2& xi, const std::vector<Neighbour>& nbrs, const Gains& g);

/// k2 (x_T - x_i) / (sigma^2 + |x_T - x_i|^2)^beta.
Vec2 attraction_term(const Vec2& xi, const Vec2& xt, const Gains& g);

/// Index into nbrs of the nearest neighbour (ties to the lowest id), or -1 when nbrs is empty.
int nearest_neighbour(const Vec2& xi, const std::vector<Neighbour>& nbrs);

/// Deterministic escape direction of agent `id` when it coincides with its nearest neighbour:
/// the unit vector at the golden angle times id, so any two ids get different directions.
Vec2 escape_direction(std::int32_t id);

/// r (x_i - x_n)/|x_i - x_n| away from a nearest neighbour at x_n; r * escape_direction(self_id) when
/// x_n coincides with x_i.
Vec2 repulsion_from(std::int32_t self_id, const Vec2& xi, const Vec2& xn, const Gains& g);

/// repulsion_from the nearest neighbour n; zero without neighbours.
Vec2 repulsion_term(std::int32_t self_id, const Vec2& xi, const std::vector<Neighbour>& nbrs,
                    const Gains& g);

/// The three terms together: dx_i/dt of the paper's law.
Vec2 paper_velocity(std::int32_t self_id, const Vec2& xi, const std::vector<Neighbour>& nbrs,
                    const Vec2& xt, const Gains& g);

}  // namespace shapeform::core
