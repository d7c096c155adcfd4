#include "geofusion/common/pose_validation.h"

#include <cmath>

namespace geofusion {

const char* toString(PoseStatus status) {
  switch (status) {
    case PoseStatus::kValid: return "valid";
    case PoseStatus::kNonFiniteTranslation: return "non-finite translation";
    case PoseStatus::kNonFiniteRotation: return "non-finite quaternion";
    case PoseStatus::kZeroQuaternion: return "zero quaternion";
    case PoseStatus::kNonUnitQuaternion: return "non-unit quaternion";
  }
  return "unknown";
}

PoseStatus checkPose(const Eigen::Vector3d& translation, const Eigen::Quaterniond& rotation,
                     double unit_tolerance) {
  if (!translation.allFinite()) return PoseStatus::kNonFiniteTranslation;
  if (!rotation.coeffs().allFinite()) return PoseStatus::kNonFiniteRotation;
  const double norm = rotation.norm();
  if (norm < 1e-9) return PoseStatus::kZeroQuaternion;
  if (std::abs(norm - 1.0) > unit_tolerance) return PoseStatus::kNonUnitQuaternion;
  return PoseStatus::kValid;
}

Eigen::Isometry3d makeIsometry(const Eigen::Vector3d& translation,
                               const Eigen::Quaterniond& rotation) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rotation.normalized().toRotationMatrix();
  T.translation() = translation;
  return T;
}

}  // namespace geofusion
