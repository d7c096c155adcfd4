// Stage II's separation factor (beyond the paper; issue 50): two estimates found interpenetrating
// after stage II must part along the contact's normal by its depth. A one-sided (hinge) residual
// on two 7-value pose blocks (pose_block.h), templated for Ceres' automatic differentiation; no
// Ceres in this header, so tests evaluate it directly.
#pragma once

#include <Eigen/Geometry>

namespace geofusion {

/// The contact point, fixed in each body's frame where it was found (p_a, p_b: the same world
/// point at the poses of the check), moves with each body; the residual is
/// weight * max(0, depth - normal . (P_b - P_a)): zero once b has left a along `normal` (world,
/// from a to b) by `depth`, and never pulling them together.
struct SeparationFactor {
  Eigen::Vector3d p_a = Eigen::Vector3d::Zero(), p_b = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double depth = 0.0;
  double weight = 1.0;

  template <typename T>
  bool operator()(const T* a, const T* b, T* r) const {
    const Eigen::Quaternion<T> Qa(a[3], a[0], a[1], a[2]), Qb(b[3], b[0], b[1], b[2]);
    const Eigen::Matrix<T, 3, 1> Ta(a[4], a[5], a[6]), Tb(b[4], b[5], b[6]);
    const Eigen::Matrix<T, 3, 1> d = (Qb * p_b.cast<T>() + Tb) - (Qa * p_a.cast<T>() + Ta);
    const T short_by = T(depth) - normal.cast<T>().dot(d);
    r[0] = short_by > T(0) ? T(weight) * short_by : T(0);
    return true;
  }
};

}  // namespace geofusion
