#include "geofusion/estimation/symmetry_axis.h"

#include <cmath>

namespace geofusion {

bool axisSeenByDetector(const ObjectModel& model) {
  return model.symmetry.type == Symmetry::Type::kContinuous &&
         orderAbout(model.appearance_symmetry, model.symmetry.axis) > 0;
}

double axialOffset(const Eigen::Vector3d& axis, const Eigen::Matrix3d& R_reference,
                   const Eigen::Matrix3d& R_measured) {
  // The rotation R(a, theta) about the axis closest to E = R_measured^T R_reference maximises
  // trace(R^T E) = cos(theta) (tr E - a'Ea) + sin(theta) a . vee(E - E') + a'Ea.
  const Eigen::Vector3d a = axis.normalized();
  const Eigen::Matrix3d E = R_measured.transpose() * R_reference;
  const Eigen::Vector3d vee(E(2, 1) - E(1, 2), E(0, 2) - E(2, 0), E(1, 0) - E(0, 1));
  return std::atan2(a.dot(vee), E.trace() - a.dot(E * a));
}

AxialAgreement axialAgreement(const ObjectModel& model, const Eigen::Matrix3d& R_reference,
                              const std::vector<AxialSample>& samples) {
  AxialAgreement out;
  out.order = std::max(1, orderAbout(model.appearance_symmetry, model.symmetry.axis));
  double c = 0.0, s = 0.0, w_sum = 0.0;
  for (const AxialSample& sample : samples) {
    if (!(sample.weight > 0.0) || !sample.R_map_obj.allFinite()) continue;
    const double theta =
        out.order * axialOffset(model.symmetry.axis, R_reference, sample.R_map_obj);
    c += sample.weight * std::cos(theta);
    s += sample.weight * std::sin(theta);
    w_sum += sample.weight;
    ++out.samples;
  }
  if (out.samples == 0) return out;
  out.resultant = std::min(1.0, std::hypot(c, s) / w_sum);
  out.mean_rad = std::atan2(s, c) / out.order;
  out.spread_rad = std::sqrt(-2.0 * std::log(std::max(out.resultant, 1e-12))) / out.order;
  return out;
}

Eigen::Matrix3d turnedToAgreement(const ObjectModel& model, const Eigen::Matrix3d& R_reference,
                                  const AxialAgreement& agreement) {
  return R_reference * Eigen::AngleAxisd(-agreement.mean_rad, model.symmetry.axis.normalized())
                           .toRotationMatrix();
}

std::shared_ptr<const ObjectModel> AppearanceModels::of(
    const std::shared_ptr<const ObjectModel>& model) {
  if (!model) return model;
  for (const auto& v : variants_)
    if (v.first == model) return v.second;
  auto variant = std::make_shared<ObjectModel>(*model);
  variant->symmetry = model->appearance_symmetry;
  variants_.emplace_back(model, variant);
  return variant;
}

}  // namespace geofusion
