// Small statistics: what the benchmarks and tools print, the medians the estimator takes.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace geofusion {

/// The p-quantile (p in [0, 1]) of `values` by the nearest rank; 0 for no values.
inline double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double rank = std::clamp(p, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  return values[static_cast<std::size_t>(rank + 0.5)];
}

}  // namespace geofusion
