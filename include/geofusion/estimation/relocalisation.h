// Relocalisation against the map on a revisit (issue 22). Coming back to a table after a drive,
// the camera pose chained from odometry can be off by more than association accepts (a degree of
// heading over a few metres moves the table by centimetres to decimetres): the detections would
// start new objects beside the mapped ones, and the free-space test would remove the mapped ones.
// Before association, the keyframe's detections (their positions in the map through the chained
// camera) are matched to the map's objects of the same class with RANSAC over pairs of
// correspondences; a rigid correction about gravity (heading and translation, the drift odometry
// makes) that brings clearly more detections onto objects than no correction is applied to the
// cameras of stage I's problem. Plain Eigen.
#pragma once

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace geofusion {

struct RelocalisationConfig {
  bool enabled = true;
  /// A detection is on an object of its class when within this, metres (after the correction).
  double inlier_m = 0.03;
  /// A correction needs at least this many detections on objects...
  int min_inliers = 4;
  /// ... and runs only when fewer than this share of the detections are on objects as they
  /// are (no correction), ...
  double max_share_on_map = 0.5;
  /// ... and is applied only when it brings at least this many times the detections onto
  /// objects that no correction does (plus one).
  double min_gain = 2.0;
  /// Corrections beyond these are refused (not a drift: a wrong match), metres (how far the
  /// detections' centre moves) and degrees.
  double max_translation_m = 1.0;
  double max_rotation_deg = 30.0;
};

/// A labelled position: a detection or a map object, in the map frame.
struct LabelledPoint {
  std::string class_name;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

struct Relocalisation {
  bool tried = false;    ///< few detections were on the map: a correction was searched
  bool applied = false;  ///< a correction was found (T_correction)
  int inliers_before = 0, inliers_after = 0;
  /// Map-frame correction: corrected pose = T_correction x chained pose.
  Eigen::Isometry3d T_correction = Eigen::Isometry3d::Identity();
};

/// The correction (rotation about `gravity` and translation) that brings the most detections
/// onto map objects of their class; see RelocalisationConfig for when one is accepted.
Relocalisation relocalise(const std::vector<LabelledPoint>& detections,
                          const std::vector<LabelledPoint>& objects, const Eigen::Vector3d& gravity,
                          const RelocalisationConfig& config);

}  // namespace geofusion
