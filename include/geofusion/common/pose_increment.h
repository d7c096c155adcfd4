// A pose increment as the optimisers here take it: translation, then rotation vector, applied on
// the right (T * increment(x): the rotation about the frame's own origin, then the translation
// in that frame). One definition for the visual odometry's covariance and its depth alignment.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace geofusion {

inline Eigen::Isometry3d poseIncrement(const Eigen::Matrix<double, 6, 1>& x) {
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  const double angle = x.tail<3>().norm();
  if (angle > 0.0) D.linear() = Eigen::AngleAxisd(angle, x.tail<3>() / angle).toRotationMatrix();
  D.translation() = x.head<3>();
  return D;
}

}  // namespace geofusion
