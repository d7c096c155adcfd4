// ORB-style RGB-D visual odometry: ORB features (OpenCV) back-projected with the registered depth,
// tracked frame to local map (the landmarks of the last few keyframes: a feature tracked when a
// keyframe is made keeps its landmark's position; optionally bundle-adjusted with the keyframe
// poses) by projection with a
// constant-velocity prediction, the pose from PnP with RANSAC (OpenCV) refined by a robust
// (Huber) reprojection fit in Ceres, keyframes inserted when the tracked share of the reference
// keyframe falls or the camera has moved enough. A frame the features cannot place (too few
// features with depth, too few inliers, an implausible jump) is aligned by its depth to the last
// placed frame (ICP); failing that it is lost, and reported; the next frames try to relocalise
// against the local map by descriptor matching alone, and after `relocalise_frames` failures the
// map restarts at the last good pose with a covariance jump. Pose uncertainty: the fit's
// Gauss-Newton covariance, composed along the keyframe chain as uncertain poses (mrpt::poses).
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/common/images.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <string>

namespace geofusion {

struct VisualOdometryConfig {
  int features = 1000;        ///< ORB features per frame
  int pyramid_levels = 4;     ///< ORB scale levels
  double scale_factor = 1.2;  ///< ... and their ratio
  int fast_threshold = 12;    ///< FAST corner threshold (grey levels)
  double min_depth_m = 0.25;  ///< features with depth outside [min, max] get no 3D point
  double max_depth_m = 4.0;
  int local_keyframes = 5;           ///< keyframes whose landmarks make the local map
  double match_radius_px = 15.0;     ///< guided matching window about the predicted projection
  int max_descriptor_distance = 64;  ///< Hamming, of 256 bits
  double ratio = 0.9;                ///< best / second best descriptor distance, at most
  double ransac_reprojection_px = 3.0;
  int ransac_iterations = 100;
  int min_inliers = 25;  ///< fewer after the refinement: lost
  /// New keyframe when the inliers fall below this share of those of the first frame after the
  /// newest keyframe, or after this much motion from it.
  double keyframe_tracked_fraction = 0.6;
  double keyframe_translation_m = 0.10;
  double keyframe_rotation_rad = 0.20;
  double max_speed_m_s = 2.0;  ///< faster camera motion is taken for a failure (lost)
  double max_turn_rad_s = 4.0;
  double pixel_sigma = 1.0;               ///< feature position noise for the covariance, pixels
  int relocalise_frames = 15;             ///< lost this many frames in a row: restart the map
  double restart_sigma_position_m = 0.3;  ///< covariance added at a restart (documented jump)
  double restart_sigma_rotation_rad = 0.3;
  /// At each new keyframe, the window's keyframe poses and landmarks refined together (local
  /// bundle adjustment, the oldest keyframe fixed; odometry/local_bundle_adjustment.h). Off by
  /// default: on the real 7-Scenes frames it made the trajectory worse (docs/visual_odometry.md).
  bool local_bundle_adjustment = false;
  int ba_iterations = 5;  ///< solver iterations of each of its two passes
  /// Depth noise of a feature at depth z in the adjustment: this times z^2 (m; 0: depth unused).
  double ba_depth_sigma_per_m2 = 0.005;
  /// A frame the features cannot place is aligned to the last placed frame's depth
  /// (point-to-plane ICP, odometry/depth_alignment.h) from the prediction, and kept when the
  /// surfaces overlap, agree and fix every direction of motion.
  bool depth_fallback = true;
  double depth_fallback_max_rmse_m = 0.01;        ///< point-to-plane RMS of the overlap, at most
  double depth_fallback_min_overlap = 0.5;        ///< share of the frame's points with a partner
  double depth_fallback_min_constraint = 0.0003;  ///< weakest direction's normalised information
};

enum class TrackingState { kNotStarted, kTracking, kLost };
const char* toString(TrackingState state);

struct VoFrameResult {
  TrackingState state = TrackingState::kNotStarted;
  bool pose_valid = false;   ///< T_odom_cam is an estimate for this frame (publish it)
  bool restarted = false;    ///< the map (re)started here: not continuous with earlier poses
  bool relocalised = false;  ///< tracking came back against the existing map
  bool by_depth =
      false;  ///< placed by its depth alone (the features could not: `problem` says why)
  bool keyframe = false;  ///< this frame became a keyframe
  Eigen::Isometry3d T_odom_cam = Eigen::Isometry3d::Identity();
  /// Pose covariance, odom frame, ROS order: x, y, z, rotation about x, y, z (m^2, rad^2).
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Identity();
  /// This frame's fit alone (its pose against the local map), camera frame, same order: how well
  /// the frame was tracked, without the drift accumulated before.
  Eigen::Matrix<double, 6, 6> frame_covariance = Eigen::Matrix<double, 6, 6>::Identity();
  int features = 0;             ///< ORB features found
  int features_with_depth = 0;  ///< ... with usable depth
  int matches = 0;              ///< 2D-3D matches to the local map
  int inliers = 0;              ///< ... consistent with the pose
  double time_ms = 0.0;         ///< wall time of track()
  std::string problem;  ///< why the pose is not valid, or why the features could not place it
};

class VisualOdometry {
 public:
  explicit VisualOdometry(const VisualOdometryConfig& config = {});
  ~VisualOdometry();
  VisualOdometry(const VisualOdometry&) = delete;
  VisualOdometry& operator=(const VisualOdometry&) = delete;

  /// One frame: grey image and depth (metres, NaN or 0 = none) registered to it, the camera's
  /// intrinsics, the frame's time. Never throws on bad input: the result says what was wrong.
  VoFrameResult track(const GrayImageView& gray, const DepthImageView& depth,
                      const PinholeIntrinsics& K, double stamp_s);
  /// Forgets the map; the next good frame starts a new one at `T_odom_cam`.
  void reset(const Eigen::Isometry3d& T_odom_cam = Eigen::Isometry3d::Identity());
  const VisualOdometryConfig& config() const;
  int numKeyframes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace geofusion
