// BOP's pose errors (Hodan et al., "BOP Challenge 2020 on 6D Object Localization", and the
// bop_toolkit's pose_error.py): MSSD and MSPD over the object's symmetries, the symmetries
// being the appearance's (BOP's models_info.json: what a detector cannot tell apart), not the
// shape's. Recall at BOP's thresholds and the average recall come from the evaluation file in
// bench_report.py (matching as bop_toolkit's pose_matching.py).
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/model/object_model.h"

#include <Eigen/Geometry>

#include <vector>

namespace geofusion {

/// A model as BOP's errors see it: its points, its diameter and its symmetry transformations
/// (rotations about the centre of the points' bounding box, where BOP's frame has its origin;
/// identity first). A continuous symmetry is discretised as bop_toolkit's
/// get_symmetry_transformations with max_sym_disc_step 0.01 (315 steps per turn).
struct BopModel {
  std::vector<Eigen::Vector3d> points;
  double diameter_m = 0.0;  ///< the largest distance between two points
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  std::vector<Eigen::Isometry3d> symmetries;  ///< model frame, identity first
};

/// BOP's view of `model`: its evaluation points, their diameter, its appearance symmetries.
BopModel bopModelOf(const ObjectModel& model);

/// The symmetry transformations of `symmetry` about `centre` (identity first; a continuous one
/// in `continuous_steps` steps, combined with the discrete ones as bop_toolkit does).
std::vector<Eigen::Isometry3d> symmetryTransformations(const Symmetry& symmetry,
                                                       const Eigen::Vector3d& centre,
                                                       int continuous_steps = 315);

/// MSSD (m): min over the symmetries S of max over the points x of |T_est x - T_true S x|
/// (bop_toolkit's pose_error.mssd: the symmetry on the truth's side).
double mssdError(const BopModel& model, const Eigen::Isometry3d& T_est,
                 const Eigen::Isometry3d& T_true);

/// MSPD (pixels): the same with the points projected by K (camera frame poses). A point behind
/// the camera makes it infinite.
double mspdError(const BopModel& model, const Eigen::Isometry3d& T_est,
                 const Eigen::Isometry3d& T_true, const PinholeIntrinsics& K);

}  // namespace geofusion
