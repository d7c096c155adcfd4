// Depth-refined measurements (beyond the paper; docs/depth_refinement.md): before a detection is
// judged by its geometric consistency, the model rendered at the detected pose (the scoring
// pass's own rendering) is aligned to the observed depth by robust point-to-plane ICP. Colour-only
// 6D estimators put objects centimetres off along the viewing ray; the refinement moves them onto
// the observed surface, guarded so that it never turns a false detection into a plausible one.
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/common/images.h"
#include "geofusion/render/consistency.h"

#include <Eigen/Geometry>

#include <memory>
#include <string>

namespace geofusion {

struct ObjectModel;

struct DepthRefinementConfig {
  bool enabled = true;   ///< off: detections are judged as they come (the paper's ablation)
  int max_points = 300;  ///< visible model surface points aligned, at most (a pixel grid)
  int min_points = 40;   ///< fewer with an observed depth: not refined
  int iterations = 10;   ///< projective association and Gauss-Newton rounds, at most
  /// Guards: a larger correction leaves the detection as it came.
  double max_translation_m = 0.05;
  double max_rotation_rad = 0.2;
  /// The first step: the detection moved along its viewing ray to where most of its visible
  /// surface meets the observed surface (the densest window of this width of the per-pixel
  /// distances along the ray).
  double ray_window_m = 0.01;
  /// ICP correspondences farther than this from the model's surface (point-to-plane) are left
  /// out; the others are weighted by a Cauchy loss of this scale.
  double gate_m = 0.02;
  double loss_scale_m = 0.004;
  /// The detection is a prior of the alignment, with the detector's rotation and lateral
  /// uncertainty (none along the ray): what the visible surface cannot fix stays as detected.
  double prior_sigma_rotation_rad = 0.08;
  double prior_sigma_lateral_m = 0.01;
  /// Converged when a round moves the pose less than this.
  double converged_translation_m = 1e-3;
  double converged_rotation_rad = 0.01;
  /// Levenberg-Marquardt damping of the Gauss-Newton steps (share of the diagonal).
  double damping = 0.2;
  /// Accepted only when the consistency score's inlier ratio improves by more than this ...
  double min_inlier_gain = 0.0;
  /// ... when at least this share of the start's and of the refined pose's rendered points
  /// (with an observed depth) is not hidden; below, the inlier ratio is undefined and the
  /// refined pose is accepted when its consistency score f_gc is higher (a start pose behind the
  /// observed surface).
  double min_visible_share = 0.25;
  /// Translation std of a refined measurement along the viewing ray (stage I); across the ray
  /// and in rotation the detector's own (stage_one.measurement_sigma_*) stays.
  double ray_sigma_m = 0.004;
};

/// Why a detection kept its pose (kAccepted: it did not).
enum class RefinementOutcome {
  kNotAttempted,   ///< refinement off, no depth, or the model cannot be rendered
  kAccepted,       ///< refined pose used
  kTooFewPoints,   ///< too little of the model has an observed depth to align to
  kBeyondGuard,    ///< the correction exceeds max_translation_m / max_rotation_rad
  kNotConverged,   ///< still moving after the last round
  kNoImprovement,  ///< the inlier ratio did not improve
};
const char* toString(RefinementOutcome outcome);
bool parseRefinementOutcome(const std::string& name, RefinementOutcome* outcome);

struct DepthRefinement {
  RefinementOutcome outcome = RefinementOutcome::kNotAttempted;
  Eigen::Isometry3d T_cam_obj = Eigen::Isometry3d::Identity();  ///< refined, or as it came
  /// Where the observed surface lies from the model's visible surface at the detected pose,
  /// along the ray (densest window; positive: behind the model). NaN when not measured.
  double ray_offset_m = 0.0;
  double correction_translation_m = 0.0;  ///< of the refined pose (also when refused)
  double correction_rotation_rad = 0.0;
  int points = 0;            ///< correspondences in the last round
  ConsistencyResult before;  ///< score at the detected pose
  ConsistencyResult after;   ///< score at the pose returned (= before unless accepted)
  bool accepted() const { return outcome == RefinementOutcome::kAccepted; }
};

/// Refines detections against a depth image with the scorer's renderer (one rendering to align,
/// one to re-score a refined pose). Not for concurrent use.
/// The refinement's acceptance: `after` (the refined pose) against `before` (the detection),
/// see DepthRefinementConfig::min_inlier_gain and min_visible_share.
bool improves(const ConsistencyResult& before, const ConsistencyResult& after,
              const DepthRefinementConfig& config);

class DepthRefiner {
 public:
  DepthRefiner(ConsistencyScorer* scorer, const DepthRefinementConfig& config);

  /// Refines the detection of `model` at T_cam_obj against `depth` (camera K); scores it before
  /// and after. With refinement off only `before` (= `after`) is computed.
  DepthRefinement refine(const std::shared_ptr<const ObjectModel>& model,
                         const Eigen::Isometry3d& T_cam_obj, const DepthImageView& depth,
                         const PinholeIntrinsics& K);

  const DepthRefinementConfig& config() const { return config_; }
  void setConfig(const DepthRefinementConfig& config) { config_ = config; }

 private:
  ConsistencyScorer* scorer_;
  DepthRefinementConfig config_;
};

/// The 3 x 3 square-root information of a refined measurement's translation (camera frame):
/// 1 / ray_sigma along the unit ray to the object, 1 / lateral_sigma across it.
Eigen::Matrix3d rayAlignedSqrtInformation(const Eigen::Vector3d& position_cam, double ray_sigma,
                                          double lateral_sigma);

}  // namespace geofusion
