#include "geofusion/odometry/local_bundle_adjustment.h"

#include "geofusion/common/ceres_compat.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace geofusion {

namespace {

// An observation's error: its pixel (and depth) against the point seen from the keyframe's pose
// (q, t: odom -> camera), each residual divided by its noise.
template <bool kDepth>
struct ObservationCost {
  ObservationCost(const BundleObservation& o, const PinholeIntrinsics& K, double sigma_px,
                  double sigma_z)
      : u(o.uv.x()),
        v(o.uv.y()),
        z(o.depth_m),
        fx(K.fx),
        fy(K.fy),
        cx(K.cx),
        cy(K.cy),
        inv_px(1.0 / sigma_px),
        inv_z(sigma_z > 0 ? 1.0 / sigma_z : 0.0) {}
  template <typename T>
  bool operator()(const T* q_cam_odom, const T* t_cam_odom, const T* X, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_cam_odom);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_cam_odom);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> P(X);
    const Eigen::Matrix<T, 3, 1> p = q * P + t;
    if (p.z() < T(1e-3)) return false;
    r[0] = (T(fx) * p.x() / p.z() + T(cx) - T(u)) * T(inv_px);
    r[1] = (T(fy) * p.y() / p.z() + T(cy) - T(v)) * T(inv_px);
    if (kDepth) r[2] = (p.z() - T(z)) * T(inv_z);
    return true;
  }
  double u, v, z, fx, fy, cx, cy, inv_px, inv_z;
};

struct PoseBlock {
  Eigen::Quaterniond q;  ///< odom -> camera
  Eigen::Vector3d t;
};

bool usesDepth(const BundleObservation& o, const LocalBundleAdjustmentOptions& options) {
  return options.depth_sigma_per_m2 > 0 && o.depth_m > 0 && std::isfinite(o.depth_m);
}

// The normalised squared error of an observation at the current estimate.
double chi2(const BundleObservation& o, const PinholeIntrinsics& K, double sigma_px, double sigma_z,
            const PoseBlock& pose, const Eigen::Vector3d& X, bool depth) {
  const Eigen::Vector3d p = pose.q * X + pose.t;
  if (p.z() < 1e-3) return std::numeric_limits<double>::infinity();
  double e = (K.project(p) - o.uv).squaredNorm() / (sigma_px * sigma_px);
  if (depth) e += (p.z() - o.depth_m) * (p.z() - o.depth_m) / (sigma_z * sigma_z);
  return e;
}

// The gauge: the fixed keyframes that take part in `problem`, else the first ones that do
// (`gauge` of them: one with depth, which fixes the scale; two without) held constant; every
// rotation on the quaternion manifold. False when no keyframe is left to adjust.
bool holdGauge(const std::vector<char>& fixed, int gauge, ceres::Problem* problem,
               std::vector<PoseBlock>* poses) {
  const std::size_t n_kf = poses->size();
  std::vector<char> hold(n_kf, 0);
  int held = 0, taking_part = 0;
  for (std::size_t k = 0; k < n_kf; ++k) {
    if (!problem->HasParameterBlock((*poses)[k].q.coeffs().data())) continue;
    ++taking_part;
    if (fixed[k]) hold[k] = 1, ++held;
  }
  for (std::size_t k = 0; k < n_kf && held < gauge; ++k) {
    if (hold[k] || !problem->HasParameterBlock((*poses)[k].q.coeffs().data())) continue;
    hold[k] = 1, ++held;
  }
  if (taking_part <= held) return false;
  for (std::size_t k = 0; k < n_kf; ++k) {
    double* q = (*poses)[k].q.coeffs().data();
    if (!problem->HasParameterBlock(q)) continue;
    ceres_compat::setManifold(problem, q, new ceres_compat::QuaternionManifold);
    if (hold[k]) {
      problem->SetParameterBlockConstant(q);
      problem->SetParameterBlockConstant((*poses)[k].t.data());
    }
  }
  return true;
}

}  // namespace

BundleAdjustmentResult localBundleAdjustment(const PinholeIntrinsics& K,
                                             const LocalBundleAdjustmentOptions& options,
                                             const std::vector<BundleObservation>& observations,
                                             const std::vector<char>& fixed,
                                             std::vector<Eigen::Isometry3d>* T_odom_cam,
                                             std::vector<Eigen::Vector3d>* points,
                                             std::vector<char>* outlier) {
  BundleAdjustmentResult result;
  outlier->assign(observations.size(), 0);
  const std::size_t n_kf = T_odom_cam->size(), n_pt = points->size();
  if (fixed.size() != n_kf) {
    result.problem = "one fixed flag a keyframe expected";
    return result;
  }
  // Points seen from two keyframes or more; the poses as blocks.
  std::vector<int> seen(n_pt, 0);
  for (const BundleObservation& o : observations) {
    if (o.keyframe < 0 || o.keyframe >= static_cast<int>(n_kf) || o.point < 0 ||
        o.point >= static_cast<int>(n_pt) || !o.uv.allFinite()) {
      result.problem = "an observation names no keyframe or point, or has no pixel";
      return result;
    }
    ++seen[static_cast<std::size_t>(o.point)];
  }
  std::vector<PoseBlock> poses(n_kf);
  for (std::size_t k = 0; k < n_kf; ++k) {
    const Eigen::Isometry3d T = (*T_odom_cam)[k].inverse();
    poses[k] = {Eigen::Quaterniond(T.linear()).normalized(), T.translation()};
  }
  std::vector<Eigen::Vector3d> X = *points;
  std::vector<double> sigma_px(observations.size()), sigma_z(observations.size());
  std::vector<char> depth(observations.size());
  for (std::size_t i = 0; i < observations.size(); ++i) {
    const BundleObservation& o = observations[i];
    sigma_px[i] = options.pixel_sigma * std::pow(options.scale_factor, std::max(0, o.level));
    depth[i] = usesDepth(o, options);
    sigma_z[i] = depth[i] ? options.depth_sigma_per_m2 * o.depth_m * o.depth_m : 0.0;
    // A point behind the camera at the start has no residual (it would stop the solver): an
    // outlier from the first pass on.
    const PoseBlock& pose = poses[static_cast<std::size_t>(o.keyframe)];
    if ((pose.q * X[static_cast<std::size_t>(o.point)] + pose.t).z() <= 1e-3) {
      (*outlier)[i] = 1;
      ++result.outliers;
    }
  }

  // Two passes: all observations, then without those still far off.
  for (int pass = 0; pass < 2; ++pass) {
    ceres::Problem problem;
    for (std::size_t i = 0; i < observations.size(); ++i) {
      const BundleObservation& o = observations[i];
      if ((*outlier)[i] || seen[static_cast<std::size_t>(o.point)] < 2) continue;
      PoseBlock& pose = poses[static_cast<std::size_t>(o.keyframe)];
      double* x = X[static_cast<std::size_t>(o.point)].data();
      ceres::CostFunction* cost =
          depth[i] ? static_cast<ceres::CostFunction*>(
                         new ceres::AutoDiffCostFunction<ObservationCost<true>, 3, 4, 3, 3>(
                             new ObservationCost<true>(o, K, sigma_px[i], sigma_z[i])))
                   : new ceres::AutoDiffCostFunction<ObservationCost<false>, 2, 4, 3, 3>(
                         new ObservationCost<false>(o, K, sigma_px[i], sigma_z[i]));
      const double delta = std::sqrt(depth[i] ? options.chi2_3d : options.chi2_2d);
      problem.AddResidualBlock(cost, new ceres::HuberLoss(delta), pose.q.coeffs().data(),
                               pose.t.data(), x);
    }
    if (problem.NumResidualBlocks() == 0) {
      result.problem = "no point is seen from two keyframes";
      return result;
    }
    if (!holdGauge(fixed, options.depth_sigma_per_m2 > 0 ? 1 : 2, &problem, &poses)) {
      result.problem = "no keyframe to adjust beside the fixed ones";
      return result;
    }
    ceres::Solver::Options solver;
    solver.linear_solver_type = ceres::SPARSE_SCHUR;
    solver.max_num_iterations = options.iterations;
    solver.num_threads = 1;
    solver.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    if (!summary.IsSolutionUsable()) {
      result.problem = "the solver failed: " + summary.message;
      return result;
    }
    if (pass == 0) {
      result.observations = problem.NumResidualBlocks();
      result.initial_cost = summary.initial_cost;
      for (std::size_t i = 0; i < observations.size(); ++i) {
        const BundleObservation& o = observations[i];
        if ((*outlier)[i] || seen[static_cast<std::size_t>(o.point)] < 2) continue;
        const double e =
            chi2(o, K, sigma_px[i], sigma_z[i], poses[static_cast<std::size_t>(o.keyframe)],
                 X[static_cast<std::size_t>(o.point)], depth[i]);
        if (e > (depth[i] ? options.chi2_3d : options.chi2_2d)) {
          (*outlier)[i] = 1;
          ++result.outliers;
        }
      }
    } else {
      result.final_cost = summary.final_cost;
    }
  }
  for (const PoseBlock& p : poses) {
    if (!p.q.coeffs().allFinite() || !p.t.allFinite()) {
      result.problem = "the solution is not finite";
      return result;
    }
  }
  for (std::size_t k = 0; k < n_kf; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = poses[k].q.normalized().toRotationMatrix();
    T.translation() = poses[k].t;
    (*T_odom_cam)[k] = T.inverse();
  }
  for (std::size_t j = 0; j < n_pt; ++j)
    if (seen[j] >= 2 && X[j].allFinite()) (*points)[j] = X[j];
  result.solved = true;
  return result;
}

}  // namespace geofusion
