#include "geofusion/evaluation/metrics.h"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <map>

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

struct AddsEvaluator::Impl {
  // Trees over the model points in the model frame: the nearest neighbour of T_true x among
  // T_est y is found as that of T_est^-1 T_true x among y (distances are rigid-invariant).
  std::map<const std::vector<Eigen::Vector3f>*, pcl::KdTreeFLANN<pcl::PointXYZ>> trees;
  pcl::KdTreeFLANN<pcl::PointXYZ>& tree(const std::vector<Eigen::Vector3f>& points) {
    auto it = trees.find(&points);
    if (it != trees.end()) return it->second;
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    cloud->reserve(points.size());
    for (const auto& p : points) cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    pcl::KdTreeFLANN<pcl::PointXYZ>& t = trees[&points];
    t.setInputCloud(cloud);
    return t;
  }
};

AddsEvaluator::AddsEvaluator() : impl_(std::make_unique<Impl>()) {}
AddsEvaluator::~AddsEvaluator() = default;

double AddsEvaluator::operator()(const std::vector<Eigen::Vector3f>& points,
                                 const Eigen::Isometry3d& T_est, const Eigen::Isometry3d& T_true) {
  if (points.empty()) return 0.0;
  const pcl::KdTreeFLANN<pcl::PointXYZ>& tree = impl_->tree(points);
  const Eigen::Isometry3d T_est_true = T_est.inverse() * T_true;
  std::vector<int> index(1);
  std::vector<float> sq(1);
  double sum = 0.0;
  for (const auto& p : points) {
    const Eigen::Vector3f q = (T_est_true * p.cast<double>()).cast<float>();
    if (tree.nearestKSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), 1, index, sq) > 0)
      sum += std::sqrt(static_cast<double>(sq[0]));
  }
  return sum / static_cast<double>(points.size());
}

double addsError(const std::vector<Eigen::Vector3f>& points, const Eigen::Isometry3d& T_est,
                 const Eigen::Isometry3d& T_true) {
  return AddsEvaluator()(points, T_est, T_true);
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
