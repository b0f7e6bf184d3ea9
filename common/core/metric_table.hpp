#pragma once
/// The one list of the swarm's convergence metrics: every optional field of core::Metrics with its
/// unit and meaning, in the column order of every metrics CSV of the project. The recorder, the
/// simulator's CSV and JSON, the supervisor's JSON, the SwarmMetrics conversion and the bench probe
/// all read it; a new metric is added here (and to core::Metrics, and to idl/SwarmMetrics.idl under
/// the same name), nowhere else.
#include <array>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <type_traits>

#include "metrics.hpp"

/// X(name, unit, description) per metric, in CSV column order. `name` is the core::Metrics member,
/// the CSV column, the JSON key and the SwarmMetrics field. The X-macro lets the DDS conversion name
/// the generated message's accessors from the same list (they cannot be reached through a table).
#define SHAPEFORM_METRICS(X)                                                                              \
  X(shape_error_mean, "shape units", "mean distance of the agents to their target points x_T(x_i)")      \
  X(shape_error_max, "shape units", "largest distance of an agent to its target point")                  \
  X(gap_cv, "1", "std/mean of the Euclidean gaps between consecutive agents along the shape")            \
  X(nn_cv, "1", "std/mean of the nearest-neighbour distances")                                           \
  X(min_separation, "shape units", "smallest pairwise distance")                                         \
  X(clusters, "count", "single-linkage clusters at core::kClusterLink")                                  \
  X(extent, "shape units", "largest pairwise distance")                                                  \
  X(centroid_error, "shape units", "tracking: distance of the agents' mean to the centre C(t)")          \
  X(ring_error, "shape units", "tracking a circle: mean | |x_i - C(t)| - scale r0 |")                    \
  X(curve_error_mean, "shape units", "mean distance to the true closest point of the shape")             \
  X(curve_error_max, "shape units", "largest distance to the true closest point of the shape")           \
  X(arc_gap_cv, "1", "std/mean of the arc-length gaps between consecutive agents")                       \
  X(min_separation_run, "shape units", "run: smallest distance of two agents at any step since the command")  \
  X(min_separation_run_time, "model time", "run: the model time min_separation_run happened")           \
  X(filter_interventions, "count", "run: agent-steps the safety filter moved (docs/SAFETY.md)")          \
  X(deadlock_sidesteps, "count", "run: deadlock sidesteps begun by the safety filter")                   \
  X(promises_broken, "count", "run: (agent, neighbour, step) found closer than safety.min_separation")    \
  X(agents_blocked, "count", "agents the safety filter holds from where the law sends them")            \
  X(fence_breaches, "count", "run: excursions of agents beyond the fence (safety.fence)")               \
  X(agents_beyond_fence, "count", "agents beyond the fence now")

namespace shapeform::core {

/// One metric of the table.
struct MetricInfo {
  std::string_view name;
  std::string_view unit;
  std::string_view description;
  bool count;  ///< an integer (written without a decimal point)
  /// The value, nullopt when undefined.
  std::optional<double> (*get)(const Metrics&);
  /// Sets the value (a count is rounded toward zero).
  void (*set)(Metrics&, double);
};

namespace detail {
template <auto Member>
std::optional<double> metric_value(const Metrics& m) {
  const auto& v = m.*Member;
  return v ? std::optional<double>(static_cast<double>(*v)) : std::nullopt;
}
template <auto Member>
void set_metric(Metrics& m, double v) {
  auto& field = m.*Member;
  field = static_cast<typename std::decay_t<decltype(field)>::value_type>(v);
}
template <class T>
struct is_count : std::false_type {};
template <>
struct is_count<std::optional<int>> : std::true_type {};
}  // namespace detail

#define SHAPEFORM_METRIC_INFO(name, unit, description)                                              \
  MetricInfo{#name, unit, description, detail::is_count<decltype(Metrics::name)>::value,            \
             &detail::metric_value<&Metrics::name>, &detail::set_metric<&Metrics::name>},
inline constexpr MetricInfo kMetricTable[] = {SHAPEFORM_METRICS(SHAPEFORM_METRIC_INFO)};
#undef SHAPEFORM_METRIC_INFO

/// The entry named `name`; throws std::invalid_argument for an unknown name (so a constant
/// expression naming an unknown metric does not compile).
constexpr const MetricInfo& metric(std::string_view name) {
  for (const MetricInfo& m : kMetricTable)
    if (m.name == name) return m;
  throw std::invalid_argument("unknown metric");
}

}  // namespace shapeform::core
