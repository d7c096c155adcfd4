#pragma once
// Ceres' two APIs for parameters that live on a manifold, in one place (docs/platforms.md):
// Ceres 2.1 and later have Manifold (2.2 removed LocalParameterization); Ceres 1.14 and 2.0, the
// versions of Ubuntu 20.04 and Debian 11, have only LocalParameterization. Both update a unit
// quaternion the same way (x' = exp(delta) * x, Eigen's coefficient order) and the translation
// by addition, so the solvers see the same problem.
//
// Only for the few .cpp files that build Ceres problems (scripts/check_modules.py allows it).
#include <ceres/ceres.h>
#include <ceres/version.h>

#if CERES_VERSION_MAJOR > 2 || (CERES_VERSION_MAJOR == 2 && CERES_VERSION_MINOR >= 1)
#define GEOFUSION_CERES_MANIFOLD 1
#include <ceres/manifold.h>
#include <ceres/product_manifold.h>
#else
#define GEOFUSION_CERES_MANIFOLD 0
#include <ceres/local_parameterization.h>
#endif

namespace geofusion {
namespace ceres_compat {

#if GEOFUSION_CERES_MANIFOLD
/// A pose block [qx qy qz qw | tx ty tz] (estimation/factors/pose_block.h).
using PoseManifold =
    ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<3>>;
/// A unit quaternion in Eigen's coefficient order.
using QuaternionManifold = ceres::EigenQuaternionManifold;
using ManifoldBase = ceres::Manifold;

/// Problem options under which the problem does not delete the manifolds it is given.
inline ceres::Problem::Options optionsKeepingManifolds() {
  ceres::Problem::Options options;
  options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  return options;
}
/// Puts an existing parameter block on `manifold` (owned by the problem unless its options say
/// otherwise).
inline void setManifold(ceres::Problem* problem, double* block, ManifoldBase* manifold) {
  problem->SetManifold(block, manifold);
}
#else
class PoseManifold : public ceres::ProductParameterization {
 public:
  PoseManifold()
      : ceres::ProductParameterization(new ceres::EigenQuaternionParameterization,
                                       new ceres::IdentityParameterization(3)) {}
};
using QuaternionManifold = ceres::EigenQuaternionParameterization;
using ManifoldBase = ceres::LocalParameterization;

inline ceres::Problem::Options optionsKeepingManifolds() {
  ceres::Problem::Options options;
  options.local_parameterization_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  return options;
}
inline void setManifold(ceres::Problem* problem, double* block, ManifoldBase* manifold) {
  problem->SetParameterization(block, manifold);
}
#endif

}  // namespace ceres_compat
}  // namespace geofusion
