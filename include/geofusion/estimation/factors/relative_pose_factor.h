// Stage I's odometry and object-measurement factors and stage II's object prior: one residual,
// the relative pose a^-1 b against a measured one (paper, "Graph Optimization", eq. for e_o and
// e_z). Templated for Ceres' automatic differentiation on two 7-value pose blocks (pose_block.h);
// no Ceres in this header, so tests evaluate it directly.
#pragma once

#include <Eigen/Geometry>

namespace geofusion {

/// Rotation residual of an error quaternion: 2 vec(q) ~ rotation vector for small angles; the
/// sign picks the short way round.
template <typename T>
Eigen::Matrix<T, 3, 1> rotationResidual(const Eigen::Quaternion<T>& q_err) {
  Eigen::Matrix<T, 3, 1> v = T(2) * q_err.vec();
  if (q_err.w() < T(0)) v = -v;
  return v;
}

/// Relative pose a^-1 b against a measured one: the odometry factor (a = x_{t-1}, b = x_t), the
/// object measurement factor (a = x_t, b = o_j) and, with a fixed identity a, the object prior.
/// Residual [W_p (t_pred - t_meas); w_q rot(q_meas^-1 q_pred)], rotation in the measured frame;
/// a continuous symmetry axis (model frame) is left free (its rotation component removed). W_p is
/// w_p I, or a 3 x 3 square-root information (a depth-refined measurement: tight along the ray).
struct RelativePoseFactor {
  RelativePoseFactor(const Eigen::Isometry3d& measured, double w_p, double w_q, bool free_axis,
                     const Eigen::Vector3d& axis)
      : RelativePoseFactor(measured, Eigen::Matrix3d(w_p * Eigen::Matrix3d::Identity()), w_q,
                           free_axis, axis) {}
  RelativePoseFactor(const Eigen::Isometry3d& measured, const Eigen::Matrix3d& W_p, double w_q,
                     bool free_axis, const Eigen::Vector3d& axis)
      : q_meas(measured.linear()),
        t_meas(measured.translation()),
        W_p(W_p),
        w_q(w_q),
        free_axis(free_axis),
        axis(axis.normalized()) {
    q_meas.normalize();
  }

  static constexpr int kResiduals = 6;

  template <typename T>
  bool operator()(const T* a, const T* b, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> Qa(a), Qb(b);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> Ta(a + 4), Tb(b + 4);
    const Eigen::Quaternion<T> q_pred = Qa.conjugate() * Qb;
    const Eigen::Matrix<T, 3, 1> t_pred = Qa.conjugate() * (Tb - Ta);
    const Eigen::Matrix<T, 3, 1> dt = W_p.cast<T>() * (t_pred - t_meas.cast<T>());
    Eigen::Matrix<T, 3, 1> v = rotationResidual<T>(q_meas.cast<T>().conjugate() * q_pred);
    if (free_axis) v -= axis.cast<T>() * axis.cast<T>().dot(v);
    for (int i = 0; i < 3; ++i) r[i] = dt[i], r[3 + i] = T(w_q) * v[i];
    return true;
  }

  Eigen::Quaterniond q_meas;
  Eigen::Vector3d t_meas;
  Eigen::Matrix3d W_p;
  double w_q;
  bool free_axis;
  Eigen::Vector3d axis;
};

}  // namespace geofusion
