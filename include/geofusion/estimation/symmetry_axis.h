// The angle about a shape's symmetry axis, taken from the detections where they agree (issue 51).
// The depth cannot see a can turn about its axis, but a detector that reads the label can: a
// can's shape is continuous and its appearance none (the tuna fish can) or a half turn (the
// master chef can, BOP's models_info.json). An object whose detections agree about the axis
// (their weighted circular mean, modulo the appearance's turns about it, has a resultant of at
// least StageOneConfig::axis_agreement_min) is estimated with its appearance symmetry: stage I,
// the folded past and stage II keep the angle; where they scatter the axis stays free.
#pragma once

#include "geofusion/model/object_model.h"

#include <Eigen/Geometry>

#include <memory>
#include <vector>

namespace geofusion {

/// True when the model's shape has a continuous axis its appearance does not share: the angle
/// about it is for the detections to say.
bool axisSeenByDetector(const ObjectModel& model);

/// The angle theta about `axis` (model frame) with R_measured Rot(axis, theta) the rotation
/// about it nearest R_reference: how far the measurement is turned short of the reference.
double axialOffset(const Eigen::Vector3d& axis, const Eigen::Matrix3d& R_reference,
                   const Eigen::Matrix3d& R_measured);

/// One detection's rotation of the object (map frame) and its weight.
struct AxialSample {
  Eigen::Matrix3d R_map_obj = Eigen::Matrix3d::Identity();
  double weight = 1.0;
};

/// How the detections agree about the axis: the weighted circular mean of their offsets from
/// the reference, each times `order` (the appearance's turns about the axis, so that a half-turn
/// symmetric can's detections agree when they are 180 degrees apart), divided by it.
struct AxialAgreement {
  int samples = 0;
  int order = 1;
  double resultant = 0.0;   ///< mean resultant length in [0, 1] (1: all agree)
  double mean_rad = 0.0;    ///< the reference turned by -mean_rad about the axis: their mean
  double spread_rad = 0.0;  ///< circular standard deviation, divided by the order
};
AxialAgreement axialAgreement(const ObjectModel& model, const Eigen::Matrix3d& R_reference,
                              const std::vector<AxialSample>& samples);

/// R_reference turned about the model's axis onto the detections' mean (agreement.mean_rad).
Eigen::Matrix3d turnedToAgreement(const ObjectModel& model, const Eigen::Matrix3d& R_reference,
                                  const AxialAgreement& agreement);

/// A copy of `model` whose `symmetry` is its appearance symmetry: what stage I, the folded past
/// and stage II are given for an object whose axis the detections fix. Made once per class and
/// kept.
class AppearanceModels {
 public:
  std::shared_ptr<const ObjectModel> of(const std::shared_ptr<const ObjectModel>& model);

 private:
  std::vector<std::pair<std::shared_ptr<const ObjectModel>, std::shared_ptr<const ObjectModel>>>
      variants_;  ///< (model, its variant)
};

}  // namespace geofusion
