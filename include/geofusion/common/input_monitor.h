// Watches a set of synchronised inputs and says, in words a user can act on, when one stops
// arriving, never arrives, or when all arrive but never synchronise. ROS-free: times are seconds
// on any monotonic clock (the ROS layer uses wall time, so a paused bag is noticed too).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace geofusion {

class InputMonitor {
 public:
  struct Config {
    /// An input with no message for this long is reported as stopped / never received, seconds.
    double stale_after_s = 3.0;
    /// All inputs arriving but no synchronised set for this long is reported, seconds.
    double sync_timeout_s = 3.0;
  };

  InputMonitor(std::vector<std::string> input_names, const Config& config, double now_s);

  /// Forgets everything seen (e.g. after a reset or a time jump) and restarts the clocks.
  void reset(double now_s);

  void onMessage(std::size_t input_index, double now_s);
  void onSynchronized(double now_s);

  /// Problems at `now_s`, one sentence each; empty when all is well.
  std::vector<std::string> problems(double now_s) const;

  std::size_t messageCount(std::size_t input_index) const { return inputs_.at(input_index).count; }
  std::size_t synchronizedCount() const { return synchronized_count_; }
  const std::vector<std::string>& inputNames() const { return names_; }

 private:
  struct InputState {
    std::size_t count = 0;
    double first_s = 0.0;
    double last_s = 0.0;
  };

  std::vector<std::string> names_;
  Config config_;
  double start_s_ = 0.0;
  std::vector<InputState> inputs_;
  std::size_t synchronized_count_ = 0;
  double last_sync_s_ = 0.0;
};

}  // namespace geofusion
