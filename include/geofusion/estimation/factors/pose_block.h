// A pose as one Ceres parameter block of 7 values: quaternion (Eigen order x, y, z, w), then
// translation; both stages put it on the product of the unit-quaternion and Euclidean manifolds.
// Plain Eigen: the factors' tests and the stages share it without Ceres in the header.
#pragma once

#include <Eigen/Geometry>

#include <array>

namespace geofusion {

struct PoseBlock {
  std::array<double, 7> x{};
  double* data() { return x.data(); }
  const double* data() const { return x.data(); }
  void set(const Eigen::Isometry3d& T) {
    Eigen::Quaterniond q(T.linear());
    q.normalize();
    x = {q.x(), q.y(), q.z(), q.w(), T.translation().x(), T.translation().y(), T.translation().z()};
  }
  Eigen::Isometry3d get() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(x[3], x[0], x[1], x[2]).normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(x[4], x[5], x[6]);
    return T;
  }
  static PoseBlock of(const Eigen::Isometry3d& T) {
    PoseBlock b;
    b.set(T);
    return b;
  }
};

}  // namespace geofusion
