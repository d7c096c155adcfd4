// Watches the detections a keyframe after the other and says when most of them are rejected as
// inconsistent with the depth image, with the likely cause: a detector whose depth is off, a
// depth image that is not registered to the colour image, wrong intrinsics. ROS-free; the node
// turns the message into a throttled warning and a WARN diagnostic, run_offline into its summary.
#pragma once

#include <deque>
#include <string>
#include <vector>

namespace geofusion {

struct DetectionReport;

struct DetectionMonitorConfig {
  int window_keyframes = 30;        ///< the last N keyframes are judged together
  int min_detections = 20;          ///< fewer usable detections in them: no verdict
  double inconsistent_below = 0.3;  ///< a detection scoring below this is rejected
  double warn_share = 0.5;          ///< warn when at least this share is rejected
};

class DetectionMonitor {
 public:
  explicit DetectionMonitor(const DetectionMonitorConfig& config = DetectionMonitorConfig())
      : config_(config) {}

  /// Adds a keyframe's detections; returns the warning that holds over the window ("" when
  /// none). Detections without a consistency score (skipped, or methods without it) do not count.
  std::string add(const std::vector<DetectionReport>& detections);

  void setConfig(const DetectionMonitorConfig& config) { config_ = config; }
  void reset() { window_.clear(); }

 private:
  struct KeyframeCounts {
    int scored = 0, rejected = 0;
    std::vector<double> rejected_offsets_m;  ///< ray offsets of the rejected ones (finite)
  };
  DetectionMonitorConfig config_;
  std::deque<KeyframeCounts> window_;
};

}  // namespace geofusion
