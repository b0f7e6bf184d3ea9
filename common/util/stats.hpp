#pragma once
/// Small order statistics shared by the rate loop (lateness) and agents (data age).
#include <optional>
#include <vector>

namespace shapeform::util {

/// Nearest-rank percentile of v: the smallest sample such that at least p % of the samples are
/// <= it (p = 0 gives the minimum, p = 100 the maximum; p is clamped to [0, 100]).
/// Reorders v (std::nth_element, O(n)); returns a sample of v, never an interpolated value.
/// nullopt when v is empty or p is NaN. Values must be finite.
std::optional<double> percentile(std::vector<double>& v, double p);

}  // namespace shapeform::util
