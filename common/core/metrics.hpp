#pragma once
/// Convergence metrics of a formation, shared by the simulator and the supervisor.
/// Undefined values (too few agents, all agents on one point) are std::nullopt, never 0 or NaN.
#include <optional>
#include <vector>

#include "compiled_command.hpp"

namespace shapeform::core {

struct Metrics {
  int agents = 0;
  std::optional<double> shape_error_mean;  ///< mean |x_i - x_T(x_i)|
  std::optional<double> shape_error_max;   ///< max |x_i - x_T(x_i)|
  std::optional<double> gap_cv;            ///< std/mean of gaps between consecutive agents
  std::optional<double> nn_cv;             ///< std/mean of nearest-neighbour distances
  std::optional<double> min_separation;    ///< smallest pairwise distance
  std::optional<int> clusters;             ///< single-linkage clusters at cluster_link
  std::optional<double> extent;            ///< largest pairwise distance
  std::optional<double> centroid_error;    ///< tracking: |mean(x) - C(t)|
  std::optional<double> ring_error;        ///< tracking a circle: mean | |x_i - C(t)| - scale r0 |; null for other shapes
  std::optional<double> curve_error_mean;  ///< mean distance to the true closest point of the shape
  std::optional<double> curve_error_max;   ///< max distance to the true closest point
  std::optional<double> arc_gap_cv;        ///< std/mean of arc-length gaps between consecutive agents
};

/// Single-linkage distance under which agents count as one cluster.
inline constexpr double kClusterLink = 0.05;

/// std/mean of values (population std; 0 for a single value); nullopt when there is none or the mean is 0
/// (below 1e-12: every value zero up to rounding).
std::optional<double> coefficient_of_variation(const std::vector<double>& v);

/// Euclidean gaps between consecutive agents along the shape: the paper's star-shaped closed shapes
/// (circle, ellipse, square, polar) ordered by angle about their centre (with wrap-around, N gaps);
/// every other shape ordered by the arc length of the agents' closest points (wrap-around when closed).
std::vector<double> consecutive_gaps(const ShapeSpec& shape, const Curve& curve, const std::vector<Vec2>& x);

/// Arc-length gaps between consecutive agents' closest points along the curve (N gaps when closed,
/// N - 1 when open).
std::vector<double> arc_gaps(const ShapeSpec& shape, const Curve& curve, const std::vector<Vec2>& x);

/// Number of single-linkage clusters at distance `link`.
int count_clusters(const std::vector<Vec2>& x, double link = kClusterLink);

/// All metrics of positions x under the command at model time t. With pairwise = false only the
/// O(N log N) ones (shape error, gap CV, tracking errors) are computed; the O(N^2) ones stay null.
Metrics compute_metrics(const CompiledCommand& cmd, const std::vector<Vec2>& x, double t, bool pairwise = true);

/// The uniformity measure convergence is judged by: the Euclidean gap CV for the paper's law (as the
/// paper measures it), the arc-length gap CV for the arc law (whose spacing is by arc length).
inline std::optional<double> uniformity(const Command& cmd, const Metrics& m) {
  return cmd.law == Law::Arc ? m.arc_gap_cv : m.gap_cv;
}

/// Settling: the first index k such that for every sample j >= k the shape error is within
/// max(band_abs, band_rel * plateau) of the plateau (the median of the last tenth of the samples, at
/// least 10) and gap CV <= gap_cv_max.
struct SettleParams {
  double band_abs = 0.02;
  double band_rel = 0.1;
  double gap_cv_max = 0.15;
};
std::optional<int> settle_index(const std::vector<double>& shape_error,
                                const std::vector<std::optional<double>>& gap_cv,
                                const SettleParams& p = {});

/// Online convergence for a live swarm: converged when, over the last `hold` span of model time,
/// the shape error stayed within a band (max - min <= max(band_abs, band_rel * mean)) and gap CV
/// stayed <= gap_cv_max. Suits the paper's law, whose plateau is off the shape and chatters.
struct ConvergenceParams : SettleParams {
  double hold = 50.0;  ///< model time units the conditions must hold
};

class ConvergenceDetector {
 public:
  using Params = ConvergenceParams;
  explicit ConvergenceDetector(Params p = Params()) : p_(p) {}
  /// Feeds one sample; a sample with an undefined error or gap CV resets the window.
  void add(double t, const std::optional<double>& shape_error, const std::optional<double>& gap_cv);
  bool converged() const { return converged_; }
  void reset();

 private:
  struct Sample {
    double t, err, cv;
  };
  Params p_;
  std::vector<Sample> window_;
  bool converged_ = false;
};

}  // namespace shapeform::core
