// Stage II's contact factors (paper, "Graph Optimization", stage II): one residual of 4 values
// between two posed surface features. Templated for Ceres' automatic differentiation on two
// 7-value pose blocks (pose_block.h); no Ceres in this header, so tests evaluate it directly.
#pragma once

#include "geofusion/estimation/contacts.h"

#include <Eigen/Geometry>

#include <cmath>

namespace geofusion {

/// The paper's contact costs. P2P: omega_q |N_u . N_v + 1| + omega_p |N_u . (C_v - C_u)|, with the
/// direction term as the vector N_u + N_v (zero at the same minimum, but its gradient does not
/// vanish there). P2C: omega_q |N_p . N_c| + omega_p |N_p . (C_c - C_p) - r|. C2C: omega_p (axis
/// distance - (r_u + r_v)). P2E (beyond the paper): omega_p N_p . (E - C_p), the edge object's
/// touching point E on the plane. Unused residual entries are 0.
struct ContactFactor {
  static constexpr int kResiduals = 4;

  ContactType type = ContactType::kPlanePlane;
  /// Features in their models' frames (centre, normal or axis, radius); for P2C and P2E `a` is
  /// the plane and `b` the curve or the touching point (c_b).
  Eigen::Vector3d c_a = Eigen::Vector3d::Zero(), n_a = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d c_b = Eigen::Vector3d::Zero(), n_b = Eigen::Vector3d::UnitZ();
  double r_a = 0.0, r_b = 0.0;
  double w_p = 1.0, w_q = 1.0;

  template <typename T>
  bool operator()(const T* a, const T* b, T* r) const {
    using std::sqrt;  // Ceres' Jet has its own, found by argument-dependent lookup
    const Eigen::Quaternion<T> Qa(a[3], a[0], a[1], a[2]), Qb(b[3], b[0], b[1], b[2]);
    const Eigen::Matrix<T, 3, 1> Ta(a[4], a[5], a[6]), Tb(b[4], b[5], b[6]);
    const Eigen::Matrix<T, 3, 1> Ca = Qa * c_a.cast<T>() + Ta, Na = Qa * n_a.cast<T>();
    const Eigen::Matrix<T, 3, 1> Cb = Qb * c_b.cast<T>() + Tb, Nb = Qb * n_b.cast<T>();
    const Eigen::Matrix<T, 3, 1> d = Cb - Ca;
    switch (type) {
      case ContactType::kPlanePlane: {
        const Eigen::Matrix<T, 3, 1> s = Na + Nb;
        r[0] = T(w_q) * s[0], r[1] = T(w_q) * s[1], r[2] = T(w_q) * s[2];
        r[3] = T(w_p) * Na.dot(d);
        break;
      }
      case ContactType::kPlaneCurve:
        r[0] = T(w_q) * Na.dot(Nb);
        r[1] = T(w_p) * (Na.dot(d) - T(r_b));
        r[2] = r[3] = T(0);
        break;
      case ContactType::kPlaneEdge:
        r[0] = T(w_p) * Na.dot(d);
        r[1] = r[2] = r[3] = T(0);
        break;
      case ContactType::kCurveCurve: {
        const Eigen::Matrix<T, 3, 1> c = Na.cross(Nb);
        const T cn2 = c.squaredNorm();
        T dist;
        if (cn2 > T(0.01)) {  // skew axes (as contacts.cpp decides): along the common normal
          const T proj = c.dot(d);
          dist = sqrt(proj * proj / cn2 + T(1e-12));
        } else {  // parallel axes: distance between the lines
          const Eigen::Matrix<T, 3, 1> perp = d - Na * Na.dot(d);
          dist = sqrt(perp.squaredNorm() + T(1e-12));
        }
        r[0] = T(w_p) * (dist - T(r_a + r_b));
        r[1] = r[2] = r[3] = T(0);
        break;
      }
    }
    return true;
  }
};

}  // namespace geofusion
