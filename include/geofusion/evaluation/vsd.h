// BOP's Visible Surface Discrepancy (Hodan et al., "On Evaluation of 6D Object Pose Estimation",
// ECCVW 2016; bop_toolkit's pose_error.vsd with visibility 'bop19'): the estimated and the true
// model are rendered (the package's OSMesa renderer) into the test image, their visible parts
// found against the test depth with tolerance delta, and the error is the share of the union of
// the visible parts where the two surfaces differ by tau or more, or only one is visible. One
// error per tau (BOP19: tau from 5 to 50 % of the object's diameter); an estimate is correct at
// threshold theta when its error is below it (theta from 0.05 to 0.5). The models are rendered
// simplified (at most 3000 triangles, 1 mm: simplifyMesh) for time.
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/model/object_model.h"

#include <Eigen/Geometry>

#include <map>
#include <memory>
#include <utility>
#include <vector>

namespace geofusion {

class OffscreenRenderer;

/// BOP19's VSD settings: delta 15 mm, tau 5 % to 50 % of the diameter in steps of 5 %.
struct VsdConfig {
  double delta_m = 0.015;
  std::vector<double> tau_fractions{0.05, 0.10, 0.15, 0.20, 0.25, 0.30, 0.35, 0.40, 0.45, 0.50};
};

/// A model at a pose in the camera frame.
struct PosedObject {
  const ObjectModel* model = nullptr;
  Eigen::Isometry3d T_cam_obj = Eigen::Isometry3d::Identity();
};

class VsdScorer {
 public:
  VsdScorer(std::shared_ptr<OffscreenRenderer> renderer, const VsdConfig& config = {});

  /// The test image: its depth (metres, row-major K.width x K.height, 0 = none), here the true
  /// scene rendered (`scene`, noise-free). False when it cannot be rendered.
  bool setScene(const PinholeIntrinsics& K, const std::vector<PosedObject>& scene);

  /// VSD errors of `model` at T_est against the truth at T_true (camera frame), one per tau of
  /// the configuration (tau = fraction x diameter_m), each in [0, 1]; empty when it cannot be
  /// rendered (no scene set, a model without mesh).
  std::vector<double> errors(const ObjectModel& model, const Eigen::Isometry3d& T_est,
                             const Eigen::Isometry3d& T_true, double diameter_m);

 private:
  int meshOf(const ObjectModel& model);
  bool renderAlone(int mesh, const Eigen::Isometry3d& T, const PixelBox& region,
                   std::vector<float>* depth);

  std::shared_ptr<OffscreenRenderer> renderer_;
  VsdConfig config_;
  std::map<const ObjectModel*, int> meshes_;
  PinholeIntrinsics K_;
  std::vector<float> scene_distance_;  ///< the test image's distances along the rays
};

/// Depth along the optical axis to distance along the ray of pixel (u, v) (BOP's
/// depth_im_to_dist_im).
double distanceOfDepth(double depth, double u, double v, const PinholeIntrinsics& K);

}  // namespace geofusion
