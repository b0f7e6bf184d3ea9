#pragma once
/// Convergence metrics of a formation, shared by the simulator and the supervisor (and the nearest
/// distances by the agents' gap figures).
/// Undefined values (too few agents, all agents on one point) are std::nullopt, never 0 or NaN.
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>
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
  // The run's figures (not of one snapshot: compute_metrics leaves them null; the simulator and the
  // supervisor fill them from the safety filter's counts and every step's positions since the command).
  std::optional<double> min_separation_run;       ///< smallest distance of two agents at any step
  std::optional<double> min_separation_run_time;  ///< model time of that step
  std::optional<int> filter_interventions;        ///< agent-steps the safety filter moved
  std::optional<int> deadlock_sidesteps;          ///< deadlock sidesteps begun
  std::optional<int> promises_broken;             ///< (agent, neighbour, step) found closer than min_separation
  std::optional<int> agents_blocked;              ///< agents the filter holds from where the law sends them now
  std::optional<int> fence_breaches;              ///< excursions beyond the fence
  std::optional<int> agents_beyond_fence;         ///< agents beyond the fence now
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

/// Each agent's distance to its nearest other agent (infinity for a lone agent): the same values as
/// comparing every pair, found on a uniform grid (about O(N) for a spread-out swarm).
std::vector<double> nearest_distances(const std::vector<Vec2>& x);

/// For each query q[k], the smallest squared distance (dx dx + dy dy, d = p[i] - q[k]) to a point p[i]
/// whose id pid[i] is not qid[k], infinity if there is none: the same values as comparing every pair,
/// found on a uniform grid (a group process's agents against every agent it hears, each tick).
std::vector<double> nearest_squared(const std::vector<Vec2>& p, const std::vector<std::int32_t>& pid,
                                    const std::vector<Vec2>& q, const std::vector<std::int32_t>& qid);

/// The largest pairwise distance (0 below two agents): the diameter of the convex hull, by rotating
/// calipers (O(N log N)).
double largest_distance(const std::vector<Vec2>& x);

/// All metrics of positions x under the command at model time t. With pairwise = false only the
/// per-agent ones (shape error, gap CV, tracking errors) are computed; the pairwise ones (nearest
/// neighbours, separation, clusters, extent) stay null.
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

/// The verdict "converged" for a live swarm (supervisor) or a run (simulator): over the last `hold`
/// span of model time
/// - the formation is ON the commanded shape: the mean shape error stayed <= on_shape_bound(cmd, p),
///   a bound relative to the shape's size that the paper's law meets on every paper scenario (its
///   plateaus: 0.17 on the circle of radius 4, 0.47 on the 4 x 2 ellipse, 0.39 on the square of half
///   side 5; bound 0.8, 0.8, 1.0);
/// - it is steady: the error stayed within a band (max - min <= max(band_abs, band_rel * mean)) and
///   the uniformity (gap CV) <= gap_cv_max (the paper's law plateaus off the shape and chatters);
///   once converged, a falling error keeps the verdict and only a rise of more than the band above
///   the span's lowest error ends it;
/// - it stopped growing: its spread (core::spread) rose by at most the on-shape bound over the span
///   (the paper's line grows for ever at about 0.2 units per model time with every agent on it).
/// Which command the agents follow is the caller's part: it feeds samples only while every agent
/// follows the command judged, and resets the detector otherwise.
struct ConvergenceParams : SettleParams {
  double hold = 50.0;          ///< model time units the conditions must hold
  double on_shape_rel = 0.2;   ///< on the shape: mean error <= on_shape_rel x the shape's size ...
  double on_shape_abs = 0.5;   ///< ... or this many shape units, whichever is larger
};

/// The largest mean shape error that counts as on the shape of cmd: max(on_shape_abs, on_shape_rel x
/// scale x the curve's size (circle: r0; ellipse: max(a, b); square: a; line: 1; others: half their
/// bounding box's diagonal)).
double on_shape_bound(const CompiledCommand& cmd, const ConvergenceParams& p);

/// The growth measure of the verdict: half the diagonal of the formation's bounding box (O(N));
/// nullopt without agents.
std::optional<double> spread(const std::vector<Vec2>& x);

class ConvergenceDetector {
 public:
  using Params = ConvergenceParams;
  /// What the verdict waits for (the first condition that failed last).
  enum class Why { Converged, NoData, OffShape, Uneven, Unsteady, Growing, Holding, Blocked };
  explicit ConvergenceDetector(Params p = Params()) : p_(p) {}
  /// Judges samples against cmd from now on (and resets). Before any command the on-shape bound and
  /// the growth check are off (the steadiness and uniformity conditions alone).
  void set_command(const CompiledCommand& cmd);
  /// Feeds one sample; a sample with an undefined error or gap CV, off the shape or uneven resets the
  /// window; spread: the formation's spread (nullopt: growth not judged).
  void add(double t, const std::optional<double>& shape_error, const std::optional<double>& gap_cv,
           const std::optional<double>& spread = std::nullopt);
  /// A sample at which the safety filter holds agents from where the law sends them (core::Swarm::
  /// blocked_agents): never converged then; the window restarts.
  void blocked();
  bool converged() const { return converged_; }
  Why why() const { return why_; }
  /// The on-shape bound in force (infinity before set_command).
  double on_shape() const { return on_shape_; }
  void reset();

 private:
  struct Sample {
    double t, err, cv;
  };
  Params p_;
  double on_shape_ = std::numeric_limits<double>::infinity();
  std::vector<Sample> window_;
  std::vector<std::pair<double, double>> spreads_;  ///< (t, spread) over the last `hold`
  bool converged_ = false;
  Why why_ = Why::NoData;
};

/// "converged", "no data", "off the shape", "uneven", "unsteady", "growing", "holding" (the span not
/// yet complete), "blocked" (the safety filter holds agents from their slots).
const char* to_string(ConvergenceDetector::Why w);

}  // namespace shapeform::core
