#include "util/stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace shapeform::util {

std::optional<double> percentile(std::vector<double>& v, double p) {
  if (v.empty() || std::isnan(p)) return std::nullopt;
  const double pc = std::clamp(p, 0.0, 100.0);
  const double n = static_cast<double>(v.size());
  // Nearest rank (1-based) = ceil(p * n / 100), at least 1; p * n first so that integer
  // products divide exactly (0.99 * 100 would round up to rank 100).
  const double rank = std::max(1.0, std::ceil(pc * n / 100.0));
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(rank) - 1);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

}  // namespace shapeform::util
