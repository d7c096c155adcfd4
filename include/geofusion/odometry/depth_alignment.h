// Frame-to-frame alignment of two depth images of one camera by their geometry alone: the
// visual odometry's fallback for a frame its features cannot place (close untextured surfaces,
// motion blur). Point-to-plane ICP from a predicted pose: points are the mean depth of
// `normal_grid` x `normal_grid` pixel blocks, normals PCL's integral-image normals on that grid (a
// window of `normal_smoothing_px`); pairs by PCL's kd-tree, only where the reference saw the point,
// away from its border; each term scaled to 1 m by 1/z^2 (a depth camera's noise grows so; the far,
// noisy floor would otherwise hold the fit near the reference's pose); Gauss-Newton steps with
// Cauchy weights (PCL's own ICP asserts inside its kd-tree on the NaN pose a degenerate step gives,
// which would abort a node). The result is accepted only where the surfaces overlap, agree within
// the noise, and fix all six directions of motion (a bare plane leaves three free, noisy or not:
// refused before any step).
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/common/images.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>

namespace geofusion {

struct DepthAlignmentOptions {
  double min_depth_m = 0.25;  ///< depth outside [min, max] is not used
  double max_depth_m = 4.0;
  int source_stride = 8;  ///< a point every n pixels of the moving frame (a multiple of the grid)
  int target_stride = 4;  ///< ... of the reference frame
  int normal_grid = 4;    ///< pixel blocks of this size make the points (mean depth) and normals
  double normal_smoothing_px = 10.0;   ///< window of the normals (integral images), pixels
  double max_correspondence_m = 0.05;  ///< ICP pairs farther apart are not used
  int iterations = 30;                 ///< Gauss-Newton steps, at most
  double max_rmse_m = 0.01;  ///< point-to-plane RMS of the overlap (terms scaled to 1 m), at most
  double min_overlap = 0.5;  ///< share of the moving frame's points with a partner, at least
  double min_constraint = 0.0003;  ///< smallest eigenvalue of the normalised information, at least
};

struct DepthAlignment {
  bool aligned = false;
  std::string problem;  ///< why not (empty when aligned)
  /// The moving (source) camera in the reference (target) camera's frame.
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();
  /// Gauss-Newton information of the fit for a right perturbation of T_target_source
  /// (translation, then rotation vector), residuals in metres with the fit's RMS as their sigma,
  /// counted as at most 100 independent pairs (neighbouring blocks' errors are correlated).
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  int points = 0;           ///< source points with depth
  double overlap = 0.0;     ///< share of them with a partner after the fit
  double rmse_m = 0.0;      ///< point-to-plane RMS over the partners
  double constraint = 0.0;  ///< smallest eigenvalue of the information per point, rotation
                            ///< scaled by the mean range (1: every direction as a facing plane)
};

/// Aligns `source` to `target` (same intrinsics) starting from `T_target_source_guess`.
DepthAlignment alignDepth(const DepthImageView& source, const DepthImageView& target,
                          const PinholeIntrinsics& K,
                          const Eigen::Isometry3d& T_target_source_guess,
                          const DepthAlignmentOptions& options);

}  // namespace geofusion
