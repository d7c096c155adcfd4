#include "geofusion/evaluation/trajectory_metrics.h"

#include "geofusion/common/atomic_file.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>

namespace geofusion {

Eigen::Isometry3d alignTrajectories(const std::vector<Eigen::Vector3d>& est,
                                    const std::vector<Eigen::Vector3d>& truth, double* rmse) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  *rmse = 0.0;
  if (est.size() < 3 || truth.size() != est.size()) return T;
  Eigen::Matrix3Xd src(3, static_cast<Eigen::Index>(est.size()));
  Eigen::Matrix3Xd dst(3, static_cast<Eigen::Index>(est.size()));
  for (std::size_t i = 0; i < est.size(); ++i) {
    src.col(static_cast<Eigen::Index>(i)) = est[i];
    dst.col(static_cast<Eigen::Index>(i)) = truth[i];
  }
  // A camera held (nearly) still leaves the rotation to the noise: then only the offset of the
  // means is taken.
  const Eigen::Vector3d mean = dst.rowwise().mean();
  const Eigen::Matrix3d spread =
      (dst.colwise() - mean) * (dst.colwise() - mean).transpose() / static_cast<double>(est.size());
  const Eigen::Vector3d extent = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(spread)
                                     .eigenvalues()
                                     .cwiseMax(0.0)
                                     .cwiseSqrt();  // ascending
  if (extent[2] < kMinAlignmentSpreadM) {
    T.translation() = mean - src.rowwise().mean();
  } else {
    T.matrix() = Eigen::umeyama(src, dst, false);
  }
  if (!T.matrix().allFinite()) return Eigen::Isometry3d::Identity();
  double sq = 0.0;
  for (std::size_t i = 0; i < est.size(); ++i) sq += (T * est[i] - truth[i]).squaredNorm();
  *rmse = std::sqrt(sq / static_cast<double>(est.size()));
  return T;
}

TrajectoryErrors trajectoryErrors(const std::vector<double>& est_stamps,
                                  const std::vector<Eigen::Isometry3d>& est,
                                  const std::vector<double>& true_stamps,
                                  const std::vector<Eigen::Isometry3d>& truth, double rpe_delta_s,
                                  double tolerance_s) {
  TrajectoryErrors e;
  e.rpe_delta_s = rpe_delta_s;
  // Pair by stamp (both sorted in time as recorded; search the nearest true stamp).
  std::vector<double> stamps;
  std::vector<Eigen::Isometry3d> P, Q;  // estimate, truth
  for (std::size_t i = 0; i < est.size() && i < est_stamps.size(); ++i) {
    const std::size_t k = static_cast<std::size_t>(
        std::lower_bound(true_stamps.begin(), true_stamps.end(), est_stamps[i]) -
        true_stamps.begin());
    std::size_t best = true_stamps.size();
    double gap = tolerance_s;
    for (std::size_t j : {k == 0 ? k : k - 1, k}) {
      if (j < true_stamps.size() && std::abs(true_stamps[j] - est_stamps[i]) <= gap) {
        gap = std::abs(true_stamps[j] - est_stamps[i]);
        best = j;
      }
    }
    if (best == true_stamps.size()) continue;
    stamps.push_back(est_stamps[i]);
    P.push_back(est[i]);
    Q.push_back(truth[best]);
  }
  e.pairs = static_cast<int>(P.size());
  if (P.size() < 3) return e;
  std::vector<Eigen::Vector3d> p, q;
  for (std::size_t i = 0; i < P.size(); ++i) {
    p.push_back(P[i].translation());
    q.push_back(Q[i].translation());
    if (i > 0) e.length_m += (Q[i].translation() - Q[i - 1].translation()).norm();
  }
  double rmse = 0.0;
  const Eigen::Isometry3d T = alignTrajectories(p, q, &rmse);
  e.ate_rmse_m = rmse;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double d = (T * p[i] - q[i]).norm();
    e.ate_mean_m += d / static_cast<double>(p.size());
    e.ate_max_m = std::max(e.ate_max_m, d);
  }
  // Relative pose error over rpe_delta_s (alignment-free).
  double st = 0.0, sr = 0.0;
  std::size_t j = 0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    while (j < P.size() && stamps[j] < stamps[i] + rpe_delta_s - tolerance_s) ++j;
    if (j >= P.size()) break;
    const Eigen::Isometry3d E = (Q[i].inverse() * Q[j]).inverse() * (P[i].inverse() * P[j]);
    st += E.translation().squaredNorm();
    const double a = Eigen::AngleAxisd(E.linear()).angle() * 180.0 / M_PI;
    sr += a * a;
    ++e.rpe_pairs;
  }
  if (e.rpe_pairs > 0) {
    e.rpe_translation_rmse_m = std::sqrt(st / e.rpe_pairs);
    e.rpe_rotation_rmse_deg = std::sqrt(sr / e.rpe_pairs);
  }
  return e;
}

bool writeTum(const std::string& path, const std::vector<double>& stamps,
              const std::vector<Eigen::Isometry3d>& poses, std::string* error) {
  return writeFileAtomically(
      path,
      [&](const std::string& tmp) {
        std::ofstream out(tmp);
        out << "# timestamp tx ty tz qx qy qz qw\n" << std::fixed;
        for (std::size_t i = 0; i < poses.size() && i < stamps.size(); ++i) {
          const Eigen::Quaterniond q(poses[i].linear());
          const Eigen::Vector3d& t = poses[i].translation();
          out << std::setprecision(6) << stamps[i] << std::setprecision(7) << " " << t.x() << " "
              << t.y() << " " << t.z() << " " << q.x() << " " << q.y() << " " << q.z() << " "
              << q.w() << "\n";
        }
        return static_cast<bool>(out);
      },
      error);
}

}  // namespace geofusion
