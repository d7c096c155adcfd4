// Relocalisation against the map on a revisit (issue 22). Coming back to a table after a drive,
// the camera pose chained from odometry can be off by more than association accepts (a degree of
// heading over a few metres moves the table by centimetres to decimetres): the detections would
// start new objects beside the mapped ones, and the free-space test would remove the mapped ones.
// Before association, the keyframe's detections (their positions in the map through the chained
// camera) are matched to the map's objects of the same class with RANSAC over pairs of
// correspondences; a rigid correction about gravity (heading and translation, the drift odometry
// makes) that brings clearly more detections onto objects than no correction is applied to the
// keyframe's camera (SceneEstimator::relocaliseCamera). Issue 32: only a correction the odometry
// can have drifted (a Mahalanobis gate on the drift accumulated since the camera last agreed with
// the map, OdometryDrift) and only one clearly ahead of the runner-up hypothesis: a camera that
// never left its table is not moved because turning about a near-symmetric layout explains the
// detections almost as well. Plain Eigen.
#pragma once

#include <Eigen/Geometry>

#include <limits>
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
  /// The odometry's drift since the camera last agreed with the map (OdometryDrift): a
  /// systematic part growing with the path, translation error per metre travelled ...
  double drift_fraction = 0.05;
  /// ... heading error per metre travelled and per radian turned, ...
  double drift_rad_per_m = 0.035;
  double drift_rad_per_rad = 0.05;
  /// ... and, per keyframe, the random part stage I's odometry factor assumes
  /// (stage_one.odometry_sigma_*). A correction whose squared Mahalanobis distance against it
  /// exceeds this is one the odometry cannot have made (chi-square, 4 dof: 18.47 = 99.9 %).
  double gate_chi2 = 18.47;
  /// Applied only when it brings at least this many more detections onto objects than the best
  /// other explanation (the runner-up, Relocalisation::runner_up): else ambiguous.
  int min_margin = 2;
};

/// How far the odometry can have drifted since the camera last agreed with the map: standard
/// deviations of the translation at the detections' centre (heading error x lever arm included)
/// and of the heading. Infinite: unknown (a resumed map), no gate.
struct OdometryDrift {
  double sigma_m = std::numeric_limits<double>::infinity();
  double sigma_rad = std::numeric_limits<double>::infinity();
  double path_m = 0.0;  ///< travelled since the anchor
  int keyframes = 0;    ///< odometry increments since the anchor
};

/// The drift of the camera path `path` (map-frame camera poses from the anchor, the last
/// keyframe agreeing with the map, to now) for detections about `centre`: the systematic part
/// grows with the path and the turns (config.drift_*), the random part with the keyframes
/// (sigma_position_m, sigma_rotation_rad a keyframe); heading errors move the centre by their
/// lever arm (the farthest camera of the path from it).
OdometryDrift accumulatedDrift(const std::vector<Eigen::Isometry3d>& path,
                               const Eigen::Vector3d& centre, const RelocalisationConfig& config,
                               double sigma_position_m, double sigma_rotation_rad);

/// What a keyframe's relocalisation decided.
enum class RelocalisationDecision {
  kNotSearched,  ///< enough detections on the map (or too few detections, or disabled)
  kApplied,      ///< T_correction applied
  kNoGain,       ///< no correction brings clearly more detections onto the map
  kBeyondDrift,  ///< the correction that would is beyond what the odometry can have drifted
  kAmbiguous,    ///< the best and the runner-up hypotheses explain the detections about equally
};
const char* toString(RelocalisationDecision decision);
bool parseRelocalisationDecision(const std::string& name, RelocalisationDecision* decision);

/// A labelled position: a detection or a map object, in the map frame.
struct LabelledPoint {
  std::string class_name;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

/// The mean position of `points` (zero for none): the detections' centre the corrections and the
/// drift are measured at.
Eigen::Vector3d centreOf(const std::vector<LabelledPoint>& points);

struct Relocalisation {
  bool tried = false;    ///< few detections were on the map: a correction was searched
  bool applied = false;  ///< a correction was found (T_correction)
  /// The detections agree with the map as they are (enough of them on objects, no search): the
  /// odometry's drift is counted from here.
  bool agreed = false;
  RelocalisationDecision decision = RelocalisationDecision::kNotSearched;
  int detections = 0;
  int inliers_before = 0;  ///< detections on objects without a correction
  int inliers_after = 0;   ///< ... with the best correction found (its support)
  /// ... with the best other explanation (a hypothesis that puts fewer than half of its
  /// detections on the objects the best one puts them on; no correction included)
  int runner_up = 0;
  /// Squared Mahalanobis distance of the best correction against `drift` (0 without a gate).
  double mahalanobis_sq = 0.0;
  OdometryDrift drift;  ///< the odometry's drift it was judged against
  /// Map-frame correction: corrected pose = T_correction x chained pose. The best correction
  /// found, applied or not (identity when none was found).
  Eigen::Isometry3d T_correction = Eigen::Isometry3d::Identity();
};

/// The correction (rotation about `gravity` and translation) that brings the most detections
/// onto map objects of their class among those the odometry's `drift` allows; see
/// RelocalisationConfig for when one is accepted.
Relocalisation relocalise(const std::vector<LabelledPoint>& detections,
                          const std::vector<LabelledPoint>& objects, const Eigen::Vector3d& gravity,
                          const RelocalisationConfig& config,
                          const OdometryDrift& drift = OdometryDrift());

}  // namespace geofusion
