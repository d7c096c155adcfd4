#include "geofusion/core/metrics.h"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>

#include <algorithm>

namespace geofusion {

double addError(const std::vector<Eigen::Vector3f>& points, const Eigen::Isometry3d& T_est,
                const Eigen::Isometry3d& T_true) {
  if (points.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& p : points) {
    const Eigen::Vector3d x = p.cast<double>();
    sum += (T_est * x - T_true * x).norm();
  }
  return sum / static_cast<double>(points.size());
}

double addsError(const std::vector<Eigen::Vector3f>& points, const Eigen::Isometry3d& T_est,
                 const Eigen::Isometry3d& T_true) {
  if (points.empty()) return 0.0;
  pcl::PointCloud<pcl::PointXYZ>::Ptr estimated(new pcl::PointCloud<pcl::PointXYZ>);
  estimated->reserve(points.size());
  for (const auto& p : points) {
    const Eigen::Vector3f q = (T_est * p.cast<double>()).cast<float>();
    estimated->push_back(pcl::PointXYZ(q.x(), q.y(), q.z()));
  }
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(estimated);
  std::vector<int> index(1);
  std::vector<float> sq(1);
  double sum = 0.0;
  for (const auto& p : points) {
    const Eigen::Vector3f q = (T_true * p.cast<double>()).cast<float>();
    if (tree.nearestKSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), 1, index, sq) > 0)
      sum += std::sqrt(static_cast<double>(sq[0]));
  }
  return sum / static_cast<double>(points.size());
}

double accuracyAuc(const std::vector<double>& errors, double max_threshold) {
  if (errors.empty() || max_threshold <= 0) return 0.0;
  // Mean over samples of the share of [0, max] thresholds the sample passes: 1 - e / max.
  double sum = 0.0;
  for (double e : errors) sum += std::max(0.0, 1.0 - e / max_threshold);
  return 100.0 * sum / static_cast<double>(errors.size());
}

double shareBelow(const std::vector<double>& errors, double threshold) {
  if (errors.empty()) return 0.0;
  const auto n =
      std::count_if(errors.begin(), errors.end(), [&](double e) { return e < threshold; });
  return static_cast<double>(n) / static_cast<double>(errors.size());
}

}  // namespace geofusion
