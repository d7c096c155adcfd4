// Local bundle adjustment of an RGB-D keyframe window (the visual odometry's back end, as
// ORB-SLAM2's local BA): the window's keyframe poses and the map points they observe, refined
// together in Ceres by each observation's reprojection error and, where the feature had depth, its
// depth error; robust (Huber), the keyframes flagged fixed held (they fix the gauge; when none
// of them sees a point seen twice, the first keyframe that does, two without depth), points
// behind a camera at the start and observations still far off after the first pass dropped as
// outliers.
#pragma once

#include "geofusion/common/camera.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace geofusion {

struct LocalBundleAdjustmentOptions {
  /// Feature position noise at the finest pyramid level, pixels; an observation at level L has
  /// this times scale_factor^L.
  double pixel_sigma = 1.0;
  double scale_factor = 1.2;
  /// Depth noise of a feature at depth z: depth_sigma_per_m2 * z^2 (m); <= 0: depth not used.
  double depth_sigma_per_m2 = 0.005;
  /// Gauss-Newton iterations of each of the two passes (before and after outlier removal).
  int iterations = 5;
  /// An observation whose normalised squared error exceeds this (chi-square, 95 %: 5.99 for two
  /// residuals, 7.81 for three) after the first pass is an outlier.
  double chi2_2d = 5.99;
  double chi2_3d = 7.81;
};

/// One feature of one keyframe, seen as one map point.
struct BundleObservation {
  int keyframe = 0;
  int point = 0;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  ///< pixel
  double depth_m = 0.0;                          ///< the feature's measured depth; <= 0: none
  int level = 0;                                 ///< pyramid level it was detected at
};

struct BundleAdjustmentResult {
  bool solved = false;
  std::string problem;        ///< why not (empty when solved)
  int observations = 0;       ///< residual blocks of the first pass
  int outliers = 0;           ///< observations dropped after the first pass
  double initial_cost = 0.0;  ///< of the first pass
  double final_cost = 0.0;    ///< of the second
};

/// Refines `T_odom_cam` (keyframe poses, those with `fixed` true held) and `points` (odom frame)
/// from `observations`. `outlier` (one flag per observation) receives the observations dropped.
/// Points seen by fewer than two keyframes are left as they are (they constrain no pose). On
/// failure nothing is changed and the result says why.
BundleAdjustmentResult localBundleAdjustment(const PinholeIntrinsics& K,
                                             const LocalBundleAdjustmentOptions& options,
                                             const std::vector<BundleObservation>& observations,
                                             const std::vector<char>& fixed,
                                             std::vector<Eigen::Isometry3d>* T_odom_cam,
                                             std::vector<Eigen::Vector3d>* points,
                                             std::vector<char>* outlier);

}  // namespace geofusion
