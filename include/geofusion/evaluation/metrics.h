// Pose accuracy metrics of the YCB-Video / PoseCNN protocol (see docs/dataset.md).
#pragma once

#include <Eigen/Geometry>

#include <memory>
#include <vector>

namespace geofusion {

/// ADD: mean distance between model points under the estimated and the true pose.
double addError(const std::vector<Eigen::Vector3f>& points, const Eigen::Isometry3d& T_est,
                const Eigen::Isometry3d& T_true);

/// ADD-S: mean distance from each point under the true pose to the closest point under the
/// estimated pose (nearest neighbour with a k-d tree; for symmetric objects).
double addsError(const std::vector<Eigen::Vector3f>& points, const Eigen::Isometry3d& T_est,
                 const Eigen::Isometry3d& T_true);

/// ADD-S that keeps one k-d tree per point set between calls (the benchmark scores many poses of a
/// few models). Keyed by the point set's address: the points must outlive the evaluator and stay
/// unchanged. addsError is this with a tree made for the one call.
class AddsEvaluator {
 public:
  AddsEvaluator();
  ~AddsEvaluator();
  double operator()(const std::vector<Eigen::Vector3f>& points, const Eigen::Isometry3d& T_est,
                    const Eigen::Isometry3d& T_true);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Area under the accuracy-threshold curve for thresholds in [0, max_threshold], in percent
/// (PoseCNN's AUC with max_threshold = 0.1 m). Errors above the range count as failures.
double accuracyAuc(const std::vector<double>& errors, double max_threshold = 0.1);

/// Share of errors below the threshold, in [0, 1].
double shareBelow(const std::vector<double>& errors, double threshold);

}  // namespace geofusion
