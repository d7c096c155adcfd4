// The calibration check of a generated sequence's noisy inputs against its ground truth
// (generate_dataset prints it; docs/dataset.md explains the figures).
#pragma once

#include "geofusion/simulation/clutter_scene.h"
#include "geofusion/simulation/sequence.h"

#include <map>
#include <string>
#include <vector>

namespace geofusion {

/// Accumulates the calibration figures of a generated sequence against ground truth: ADD-S per
/// class of true-class detections (AUC 0-10 cm, share under 2 cm), misses, class swaps, false
/// positives, and the depth noise (rms against the clean render, share of holes).
class SequenceCalibration {
 public:
  /// Objects with at least this many visible pixels count as detectable (for the miss rate);
  /// depth statistics over pixels whose clean depth is below `max_depth_m` (the table top).
  explicit SequenceCalibration(int min_visible_pixels = 250, double max_depth_m = 1.5)
      : min_visible_pixels_(min_visible_pixels), max_depth_m_(max_depth_m) {}
  void add(const ClutterScene& scene, const Eigen::Isometry3d& T_map_optical,
           const SequenceFrame& frame);
  struct ClassStats {
    int detections = 0;
    double auc = 0.0;      ///< ADD-S AUC (0-10 cm), percent
    double below_2cm = 0;  ///< share, [0, 1]
  };
  std::map<std::string, ClassStats> perClass() const;
  ClassStats overall() const;
  /// ADD-S of every true-class detection added so far, metres.
  std::vector<double> errors() const;
  int detections() const { return detections_; }
  int falsePositives() const { return false_positives_; }
  int classSwaps() const { return swaps_; }
  int missed() const { return missed_; }  ///< detectable objects not detected
  int detectable() const { return detectable_; }
  double depthNoiseRms() const;  ///< metres
  double holeShare() const;      ///< [0, 1]
  /// Human-readable table: one line a class, then the overall and depth figures.
  std::string report() const;

 private:
  int min_visible_pixels_;
  double max_depth_m_;
  std::map<std::string, std::vector<double>> adds_;
  int detections_ = 0, false_positives_ = 0, swaps_ = 0, missed_ = 0, detectable_ = 0;
  double depth_sq_sum_ = 0.0;
  long depth_valid_ = 0, depth_holes_ = 0;
};

}  // namespace geofusion
