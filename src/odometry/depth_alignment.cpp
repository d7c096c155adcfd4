#include "geofusion/odometry/depth_alignment.h"

#include "geofusion/common/pose_increment.h"

#include <pcl/features/integral_image_normal.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/brute_force.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace geofusion {

namespace {

using Cloud = pcl::PointCloud<pcl::PointNormal>;

// Points (camera frame) with their surface normals on a grid of `grid` x `grid` pixel blocks,
// every (stride / grid)-th block taken. Each block's point is its pixels' mean depth at its
// centre (blocks across a depth edge, a spread over 3 % of the depth, or half empty: none), so
// a sample carries a block's noise, not a pixel's; the normals are PCL's integral-image normals
// (the average 3D gradient over `normal_smoothing_px`, none across depth edges) on that grid
// (normals from single noisy pixels make a bare plane look curved and hide the directions it
// leaves free). Points nearer the border than the window are left out.
Cloud::Ptr cloudWithNormals(const DepthImageView& depth, const PinholeIntrinsics& K, int grid,
                            int stride, const DepthAlignmentOptions& o) {
  const int g = std::max(1, grid), step = std::max(1, stride / g);
  pcl::PointCloud<pcl::PointXYZ>::Ptr organised(new pcl::PointCloud<pcl::PointXYZ>);
  organised->width = static_cast<std::uint32_t>(depth.width / g);
  organised->height = static_cast<std::uint32_t>(depth.height / g);
  organised->is_dense = false;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  organised->points.assign(static_cast<std::size_t>(organised->width) * organised->height,
                           pcl::PointXYZ(nan, nan, nan));
  for (int bv = 0; bv < static_cast<int>(organised->height); ++bv) {
    for (int bu = 0; bu < static_cast<int>(organised->width); ++bu) {
      double sum = 0.0, lo = std::numeric_limits<double>::infinity(), hi = 0.0;
      int count = 0;
      for (int v = bv * g; v < (bv + 1) * g; ++v) {
        for (int u = bu * g; u < (bu + 1) * g; ++u) {
          const float z = depth.at(u, v);
          if (!std::isfinite(z) || z < o.min_depth_m || z > o.max_depth_m) continue;
          sum += z, ++count, lo = std::min<double>(lo, z), hi = std::max<double>(hi, z);
        }
      }
      if (2 * count < g * g || hi - lo > 0.03 * lo) continue;
      const Eigen::Vector3d p =
          K.backProject(bu * g + 0.5 * (g - 1), bv * g + 0.5 * (g - 1), sum / count);
      organised->at(bu, bv) = pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                            static_cast<float>(p.z()));
    }
  }
  pcl::PointCloud<pcl::Normal> normals;
  pcl::IntegralImageNormalEstimation<pcl::PointXYZ, pcl::Normal> estimate;
  estimate.setNormalEstimationMethod(estimate.AVERAGE_3D_GRADIENT);
  estimate.setMaxDepthChangeFactor(0.02f);
  estimate.setNormalSmoothingSize(static_cast<float>(o.normal_smoothing_px / g));
  estimate.setDepthDependentSmoothing(false);
  // Integral images need no neighbour search; the default for an organised cloud (PCL's
  // OrganizedNeighbor) would fit a projection matrix first and complain about a bare plane.
  estimate.setSearchMethod(
      pcl::search::BruteForce<pcl::PointXYZ>::Ptr(new pcl::search::BruteForce<pcl::PointXYZ>));
  estimate.setInputCloud(organised);
  estimate.compute(normals);
  Cloud::Ptr out(new Cloud);
  const int margin = static_cast<int>(std::ceil(o.normal_smoothing_px / g));
  for (int v = margin; v < static_cast<int>(organised->height) - margin; v += step) {
    for (int u = margin; u < static_cast<int>(organised->width) - margin; u += step) {
      const pcl::PointXYZ& p = organised->at(u, v);
      const pcl::Normal& n = normals.at(u, v);
      if (!std::isfinite(p.z) || !std::isfinite(n.normal_x) || !std::isfinite(n.normal_y) ||
          !std::isfinite(n.normal_z))
        continue;
      pcl::PointNormal q;
      q.x = p.x, q.y = p.y, q.z = p.z;
      q.normal_x = n.normal_x, q.normal_y = n.normal_y, q.normal_z = n.normal_z;
      out->push_back(q);
    }
  }
  return out;
}

std::string format(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

constexpr double kIndependentPairs = 100.0;

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

// The point-to-plane terms of the source points at pose T: each point's nearest target point
// (PCL's kd-tree), kept within the correspondence distance and `gate_m` of its plane; per term the
// residual and its Jacobian for a right perturbation of T (translation, rotation vector).
struct PlaneTerms {
  std::vector<double> r;
  std::vector<Vector6d> J;
  std::vector<Eigen::Vector3d> p;  ///< the source points used
};
PlaneTerms planeTerms(const Cloud& source, const Cloud& target,
                      const pcl::KdTreeFLANN<pcl::PointNormal>& tree, const Eigen::Isometry3d& T,
                      const PinholeIntrinsics& K, const DepthAlignmentOptions& o, double gate_m) {
  PlaneTerms out;
  const Eigen::Matrix3d Rt = T.linear().transpose();
  std::vector<int> index(1);
  std::vector<float> d2(1);
  const double margin = o.normal_smoothing_px;
  for (const pcl::PointNormal& s : source.points) {
    const Eigen::Vector3d p(s.x, s.y, s.z), q = T * p;
    // Only where the reference saw it, away from its border (no partner outside its view; the
    // nearest points on its border would pull the frame back toward it).
    if (!(q.z() > 0.0)) continue;
    const Eigen::Vector2d uv = K.project(q);
    if (!(uv.x() >= margin && uv.y() >= margin && uv.x() < K.width - margin &&
          uv.y() < K.height - margin))
      continue;
    pcl::PointNormal query;
    query.x = static_cast<float>(q.x()), query.y = static_cast<float>(q.y()),
    query.z = static_cast<float>(q.z());
    if (tree.nearestKSearch(query, 1, index, d2) < 1) continue;
    if (d2[0] > o.max_correspondence_m * o.max_correspondence_m) continue;
    const pcl::PointNormal& t = target.points[static_cast<std::size_t>(index[0])];
    const Eigen::Vector3d n(t.normal_x, t.normal_y, t.normal_z);
    // A depth camera's noise grows with the square of the depth: each term scaled to 1 m (the far,
    // noisy floor would otherwise hold the fit near the reference's own pose).
    const double scale = 1.0 / std::max(p.z() * p.z(), 0.01);
    const double r = scale * n.dot(q - Eigen::Vector3d(t.x, t.y, t.z));
    if (std::abs(r) > gate_m) continue;
    const Eigen::Vector3d m = Rt * n;  // the target's normal in the source frame
    Vector6d J;
    J << m, p.cross(m);
    out.r.push_back(r);
    out.J.push_back(scale * J);
    out.p.push_back(p);
  }
  return out;
}

// How well the terms fix each direction of motion (Gelfand et al. 2003, "Geometrically stable
// sampling for the ICP algorithm"): the smallest eigenvalue of their information per term, about
// the points' centroid, rotation scaled by their spread (1 would be every term fixing that
// direction fully; a bare plane gives 0 for its three free directions). The normals' noise
// adds a floor (about 0.008 for a Kinect v1 plane at 1.5 m); the directions it alone "fixes"
// stay near the prediction in the fit.
double weakestDirection(const PlaneTerms& terms) {
  if (terms.J.empty()) return 0.0;
  const double n = static_cast<double>(terms.J.size());
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : terms.p) c += p / n;
  double spread2 = 0.0;
  for (const Eigen::Vector3d& p : terms.p) spread2 += (p - c).squaredNorm() / n;
  const double spread = std::sqrt(std::max(spread2, 1e-12));
  Matrix6d H = Matrix6d::Zero();
  for (std::size_t i = 0; i < terms.J.size(); ++i) {
    const Eigen::Vector3d m = terms.J[i].head<3>();  // the scaled normal
    Vector6d J;
    J << m, (terms.p[i] - c).cross(m) / spread;
    H += J * J.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Matrix6d> E(H / n);
  return E.eigenvalues()(0);
}

// Gauss-Newton on the point-to-plane terms (Cauchy weights at the RMS limit) from the guess;
// stops when the step is below 0.1 mm and 0.006 deg. False, with the reason, when the terms
// leave a direction free or the step is not finite.
bool pointToPlane(const Cloud& source, const Cloud& target,
                  const pcl::KdTreeFLANN<pcl::PointNormal>& tree, const PinholeIntrinsics& K,
                  const DepthAlignmentOptions& o, DepthAlignment* a) {
  Eigen::Isometry3d T = a->T_target_source;
  for (int it = 0; it < std::max(1, o.iterations); ++it) {
    const PlaneTerms terms = planeTerms(source, target, tree, T, K, o, o.max_correspondence_m);
    a->constraint = weakestDirection(terms);
    if (terms.J.size() < 100 || a->constraint < o.min_constraint) {
      a->problem = "the geometry leaves a direction free (constraint " + format(a->constraint) +
                   " below " + format(o.min_constraint) + ", " + std::to_string(terms.J.size()) +
                   " pairs)";
      return false;
    }
    Matrix6d H = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
    for (std::size_t i = 0; i < terms.J.size(); ++i) {
      const double u = terms.r[i] / o.max_rmse_m, w = 1.0 / (1.0 + u * u);
      H += w * terms.J[i] * terms.J[i].transpose();
      g += w * terms.r[i] * terms.J[i];
    }
    const Vector6d x = H.ldlt().solve(-g);
    if (!x.allFinite()) {
      a->problem = "the alignment's step is not finite";
      return false;
    }
    T = T * poseIncrement(x);
    if (x.head<3>().norm() < 1e-4 && x.tail<3>().norm() < 1e-4) break;
  }
  a->T_target_source = T;
  return true;
}

// How well the fitted pose is supported: the partners within three RMS limits of their plane;
// the point-to-plane RMS over them, the overlap, the information of the fit.
void scoreAlignment(const Cloud& source, const Cloud& target,
                    const pcl::KdTreeFLANN<pcl::PointNormal>& tree, const PinholeIntrinsics& K,
                    const DepthAlignmentOptions& o, DepthAlignment* a) {
  const PlaneTerms terms =
      planeTerms(source, target, tree, a->T_target_source, K, o, 3.0 * o.max_rmse_m);
  a->overlap = source.empty() ? 0.0 : static_cast<double>(terms.J.size()) / source.size();
  a->constraint = weakestDirection(terms);
  if (terms.J.size() < 6) return;
  double sum_r2 = 0.0;
  Matrix6d H = Matrix6d::Zero();
  for (std::size_t i = 0; i < terms.J.size(); ++i) {
    sum_r2 += terms.r[i] * terms.r[i];
    H += terms.J[i] * terms.J[i].transpose();
  }
  a->rmse_m = std::sqrt(sum_r2 / static_cast<double>(terms.J.size()));
  const double sigma = std::max(a->rmse_m, 1e-4);
  // Neighbouring blocks share the camera's correlated errors (its calibration, the blocks' mean
  // depth): the information of at most kIndependentPairs pairs, not of thousands (which would
  // claim 0.25 mm on the weakest direction where the gtest's bare frames are 0.5-1 mm off).
  const double n = static_cast<double>(terms.J.size());
  a->information = H / (sigma * sigma) * std::min(1.0, kIndependentPairs / n);
}

}  // namespace

DepthAlignment alignDepth(const DepthImageView& source, const DepthImageView& target,
                          const PinholeIntrinsics& K,
                          const Eigen::Isometry3d& T_target_source_guess,
                          const DepthAlignmentOptions& options) {
  DepthAlignment a;
  if (!source.data || !target.data || source.width != K.width || source.height != K.height ||
      target.width != K.width || target.height != K.height ||
      !T_target_source_guess.matrix().allFinite()) {
    a.problem = "depth images, camera and guess disagree";
    return a;
  }
  const Cloud::Ptr src =
      cloudWithNormals(source, K, options.normal_grid, options.source_stride, options);
  const Cloud::Ptr tgt =
      cloudWithNormals(target, K, options.normal_grid, options.target_stride, options);
  a.points = static_cast<int>(src->size());
  if (src->size() < 100 || tgt->size() < 100) {
    a.problem = "too little depth (" + std::to_string(src->size()) + " and " +
                std::to_string(tgt->size()) + " points)";
    return a;
  }
  pcl::KdTreeFLANN<pcl::PointNormal> tree;
  tree.setInputCloud(tgt);
  a.T_target_source = T_target_source_guess;
  if (!pointToPlane(*src, *tgt, tree, K, options, &a)) return a;
  scoreAlignment(*src, *tgt, tree, K, options, &a);
  if (a.overlap < options.min_overlap) {
    a.problem = "overlap " + format(a.overlap) + " below " + format(options.min_overlap);
  } else if (a.rmse_m > options.max_rmse_m) {
    a.problem = "RMS " + format(a.rmse_m) + " m above " + format(options.max_rmse_m);
  } else if (a.constraint < options.min_constraint) {
    a.problem = "the geometry leaves a direction free (constraint " + format(a.constraint) +
                " below " + format(options.min_constraint) + ")";
  }
  a.aligned = a.problem.empty();
  return a;
}

}  // namespace geofusion
