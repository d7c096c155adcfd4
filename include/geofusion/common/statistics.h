// Small statistics: what the benchmarks and tools print, the medians the estimator takes, the
// background map's cost (BackgroundWorker measures it, the results file records it).
#pragma once

#include <algorithm>
#include <cstddef>
#include <ctime>
#include <vector>

namespace geofusion {

/// The p-quantile (p in [0, 1]) of `values` by the nearest rank; 0 for no values.
inline double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double rank = std::clamp(p, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  return values[static_cast<std::size_t>(rank + 0.5)];
}

/// The calling thread's CPU time, ms: what work costs on its core, whatever else runs.
inline double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

/// What the background's insertions have cost so far.
struct BackgroundStats {
  std::size_t submitted = 0;  ///< keyframes handed over
  std::size_t inserted = 0;   ///< ... inserted
  std::size_t skipped = 0;    ///< ... replaced by a newer one before their turn (threaded only)
  std::size_t still = 0;      ///< ... passed over: the camera had hardly moved (wanted())
  double last_ms = 0.0;       ///< the last insertion's time (its thread's CPU time)
  double total_ms = 0.0;      ///< every insertion's CPU time summed (the checks' included)
  double p50_ms = 0.0, p95_ms = 0.0, max_ms = 0.0;  ///< over the insertions
  /// total_ms over the keyframes submitted: the background's cost a keyframe on one core.
  double amortisedMs() const { return submitted ? total_ms / submitted : 0.0; }
};

}  // namespace geofusion
