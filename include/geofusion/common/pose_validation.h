// Checks that a pose received from outside is usable before anything is computed from it.
#pragma once

#include <Eigen/Geometry>

namespace geofusion {

enum class PoseStatus {
  kValid = 0,
  kNonFiniteTranslation,
  kNonFiniteRotation,
  kZeroQuaternion,
  kNonUnitQuaternion,
};

/// Human-readable name of a status, e.g. "non-unit quaternion".
const char* toString(PoseStatus status);

/// Default tolerance on | |q| - 1 |: generous enough for float32 messages, tight enough to reject
/// quaternions that were never normalised.
constexpr double kUnitQuaternionTolerance = 1e-3;

/// Classifies a translation + quaternion pair. A quaternion counts as zero when its norm is below
/// 1e-9, and as non-unit when | |q| - 1 | > unit_tolerance.
PoseStatus checkPose(const Eigen::Vector3d& translation, const Eigen::Quaterniond& rotation,
                     double unit_tolerance = kUnitQuaternionTolerance);

/// Builds a rigid transform; the quaternion is renormalised (call checkPose first).
Eigen::Isometry3d makeIsometry(const Eigen::Vector3d& translation,
                               const Eigen::Quaterniond& rotation);

}  // namespace geofusion
