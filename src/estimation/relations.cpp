#include "geofusion/estimation/relations.h"

#include "geofusion/model/mesh.h"
#include "geofusion/model/surface_features.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/sample_consensus/sac_model_plane.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace geofusion {

namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

// The keyframe's depth points within range, in the map frame, every pixel_stride-th row/column.
Cloud::Ptr mapPoints(const DepthImageView& depth, const PinholeIntrinsics& K,
                     const Eigen::Isometry3d& T_map_cam, const SupportPlaneConfig& config) {
  Cloud::Ptr cloud(new Cloud);
  const int stride = std::max(1, config.pixel_stride);
  for (int v = 0; v < K.height; v += stride) {
    for (int u = 0; u < K.width; u += stride) {
      const float z = depth.at(u, v);
      if (!(z > 0.f) || !std::isfinite(z) || z > config.max_range_m) continue;
      const Eigen::Vector3d p = T_map_cam * K.backProject(u, v, z);
      cloud->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                     static_cast<float>(p.z())));
    }
  }
  return cloud;
}

// A plane n . p + d = 0 with its inliers.
struct PlaneFit {
  Eigen::Vector4f coefficients = Eigen::Vector4f::Zero();
  std::vector<int> inliers;
};

// The dominant plane within max_tilt of horizontal: RANSAC (PCL SACSegmentation).
PlaneFit searchPlane(const Cloud::Ptr& cloud, const Eigen::Vector3d& up,
                     const SupportPlaneConfig& config) {
  pcl::SACSegmentation<pcl::PointXYZ> seg;
  seg.setOptimizeCoefficients(true);
  seg.setModelType(pcl::SACMODEL_PERPENDICULAR_PLANE);
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setAxis(up.cast<float>());
  seg.setEpsAngle(config.max_tilt_deg * M_PI / 180.0);
  seg.setDistanceThreshold(config.distance_threshold_m);
  seg.setMaxIterations(config.max_iterations);
  seg.setInputCloud(cloud);
  pcl::PointIndices inliers;
  pcl::ModelCoefficients coefficients;
  seg.segment(inliers, coefficients);
  PlaneFit fit;
  if (coefficients.values.size() != 4) return fit;
  fit.coefficients = Eigen::Vector4f(coefficients.values.data());
  fit.inliers = std::move(inliers.indices);
  return fit;
}

// The known plane followed into this keyframe: the points within distance_threshold of it, the
// least-squares plane through them (PCL's plane model), its inliers. No RANSAC: the plane of the
// previous keyframes is the hypothesis.
PlaneFit followPlane(const Cloud::Ptr& cloud, const SupportPlane& known,
                     const SupportPlaneConfig& config) {
  pcl::SampleConsensusModelPlane<pcl::PointXYZ> model(cloud);
  const Eigen::Vector4f prior(
      static_cast<float>(known.normal.x()), static_cast<float>(known.normal.y()),
      static_cast<float>(known.normal.z()), static_cast<float>(-known.height));
  PlaneFit fit;
  std::vector<int> near;
  model.selectWithinDistance(prior, config.distance_threshold_m, near);
  if (static_cast<int>(near.size()) < std::max(4, config.min_inliers)) return fit;
  Eigen::VectorXf refined;
  model.optimizeModelCoefficients(near, prior, refined);
  if (refined.size() != 4 || !refined.allFinite()) return fit;
  fit.coefficients = refined;
  model.selectWithinDistance(refined, config.distance_threshold_m, fit.inliers);
  return fit;
}

// The support plane of a fit: normal up and within max_tilt of it, in-plane axes, the inliers'
// extent. Invalid with too few inliers or too much tilt.
SupportPlane supportPlaneOf(const PlaneFit& fit, const Cloud& cloud, const Eigen::Vector3d& up,
                            const SupportPlaneConfig& config) {
  SupportPlane out;
  if (static_cast<int>(fit.inliers.size()) < config.min_inliers) return out;
  Eigen::Vector3d n = fit.coefficients.head<3>().cast<double>();
  double d = fit.coefficients[3];
  const double norm = n.norm();
  if (!(norm > 0.0)) return out;
  n /= norm, d /= norm;
  if (n.dot(up) < 0) n = -n, d = -d;
  if (n.dot(up) < std::cos(config.max_tilt_deg * M_PI / 180.0)) return out;
  out.normal = n;
  out.height = -d;  // n . p + d = 0  =>  n . p = -d
  // In-plane axes: x along the map x projected on the plane.
  Eigen::Vector3d ax = Eigen::Vector3d::UnitX() - n * n.x();
  if (ax.norm() < 1e-3) ax = Eigen::Vector3d::UnitY() - n * n.y();
  ax.normalize();
  const Eigen::Vector3d ay = n.cross(ax);
  out.axes.col(0) = ax, out.axes.col(1) = ay, out.axes.col(2) = n;
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (int i : fit.inliers) {
    const Eigen::Vector3d p =
        cloud.points[static_cast<std::size_t>(i)].getVector3fMap().cast<double>();
    const Eigen::Vector2d q(p.dot(ax), p.dot(ay));
    lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
  }
  const Eigen::Vector2d mid = 0.5 * (lo + hi);
  out.size = hi - lo;
  out.centre = ax * mid.x() + ay * mid.y() + n * out.height;
  out.inliers = static_cast<int>(fit.inliers.size());
  out.observations = 1;
  out.valid = true;
  return out;
}

}  // namespace

SupportPlane estimateSupportPlane(const DepthImageView& depth, const PinholeIntrinsics& K,
                                  const Eigen::Isometry3d& T_map_cam,
                                  const Eigen::Vector3d& gravity, const SupportPlaneConfig& config,
                                  const SupportPlane* known) {
  if (!depth.data || depth.width != K.width || depth.height != K.height || !K.valid()) return {};
  const Cloud::Ptr cloud = mapPoints(depth, K, T_map_cam, config);
  if (static_cast<int>(cloud->size()) < config.min_inliers) return {};
  const Eigen::Vector3d up = -gravity.normalized();
  if (known && known->valid) {
    const SupportPlane followed =
        supportPlaneOf(followPlane(cloud, *known, config), *cloud, up, config);
    const int usual = known->inliers / std::max(1, known->observations);
    if (followed.valid && 2 * followed.inliers >= usual) return followed;
  }
  return supportPlaneOf(searchPlane(cloud, up, config), *cloud, up, config);
}

void fuseSupportPlane(const SupportPlane& observed, SupportPlane* fused,
                      double max_height_difference_m) {
  if (!observed.valid) return;
  if (!fused->valid) {
    *fused = observed;
    return;
  }
  if (std::abs(observed.height - fused->height) > max_height_difference_m) {
    // Another surface (the floor, a shelf, a big box top): keep the better supported one.
    if (observed.inliers > 2 * fused->inliers / std::max(1, fused->observations)) *fused = observed;
    return;
  }
  const double w0 = fused->inliers, w1 = observed.inliers, w = w0 + w1;
  Eigen::Vector3d n = (w0 * fused->normal + w1 * observed.normal).normalized();
  const double height = (w0 * fused->height + w1 * observed.height) / w;
  // Union of the two extents in the fused axes.
  const Eigen::Vector3d ax = fused->axes.col(0), ay = fused->axes.col(1);
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (const SupportPlane* p : {static_cast<const SupportPlane*>(fused), &observed}) {
    for (int sx = -1; sx <= 1; sx += 2) {
      for (int sy = -1; sy <= 1; sy += 2) {
        const Eigen::Vector3d corner = p->centre + 0.5 * sx * p->size.x() * p->axes.col(0) +
                                       0.5 * sy * p->size.y() * p->axes.col(1);
        const Eigen::Vector2d q(corner.dot(ax), corner.dot(ay));
        lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
      }
    }
  }
  Eigen::Vector3d new_ax = (ax - n * n.dot(ax)).normalized();
  fused->normal = n;
  fused->height = height;
  fused->axes.col(0) = new_ax;
  fused->axes.col(1) = n.cross(new_ax);
  fused->axes.col(2) = n;
  const Eigen::Vector2d mid = 0.5 * (lo + hi);
  fused->size = hi - lo;
  fused->centre = new_ax * mid.x() + fused->axes.col(1) * mid.y() + n * height;
  fused->inliers = static_cast<int>(std::min(w, 1e9));
  fused->observations += observed.observations;
}

std::shared_ptr<ObjectModel> supportPlaneModel(const SupportPlane& plane,
                                               Eigen::Isometry3d* T_map_model, double thickness_m) {
  auto model = std::make_shared<ObjectModel>();
  model->name = "support_plane";
  const Eigen::Vector3d size(std::max(plane.size.x(), 0.05), std::max(plane.size.y(), 0.05),
                             thickness_m);
  model->mesh = makeBox(size);
  model->extents = size.cast<float>();
  model->box = Eigen::AlignedBox3f(-0.5f * model->extents, 0.5f * model->extents);
  // Only the top face matters for contacts: one plane feature, outward normal +z.
  PlaneFeature top;
  top.center = Eigen::Vector3d(0, 0, 0.5 * thickness_m);
  top.normal = Eigen::Vector3d::UnitZ();
  const double hx = 0.5 * size.x(), hy = 0.5 * size.y(), hz = 0.5 * thickness_m;
  top.boundary = {{-hx, -hy, hz}, {hx, -hy, hz}, {hx, hy, hz}, {-hx, hy, hz}};
  top.area_m2 = size.x() * size.y();
  model->features.planes.push_back(top);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = plane.axes;
  T.translation() = plane.centre - plane.normal * (0.5 * thickness_m);
  if (T_map_model) *T_map_model = T;
  return model;
}

std::pair<double, double> hullHeightsAbove(const ObjectModel& model,
                                           const Eigen::Isometry3d& T_map_obj,
                                           const Eigen::Vector3d& normal, double height,
                                           Eigen::Vector3d* lowest_point) {
  double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
  const TriangleMesh& hull = model.collision_hull.empty() ? model.mesh : model.collision_hull;
  for (const Eigen::Vector3f& v : hull.vertices) {
    const Eigen::Vector3d p = T_map_obj * v.cast<double>();
    const double h = normal.dot(p) - height;
    if (h < lowest && lowest_point) *lowest_point = p;
    lowest = std::min(lowest, h), highest = std::max(highest, h);
  }
  return {lowest, highest};
}

double depthThroughPlane(const SupportPlane& plane, const ObjectModel& model,
                         const Eigen::Isometry3d& T_map_obj, double margin_m) {
  if (!plane.valid) return 0.0;
  const Eigen::Vector3d in_plane =
      plane.axes.transpose() * (T_map_obj.translation() - plane.centre);
  if (std::abs(in_plane.x()) > 0.5 * plane.size.x() + margin_m ||
      std::abs(in_plane.y()) > 0.5 * plane.size.y() + margin_m)
    return 0.0;
  return std::max(0.0, -hullHeightsAbove(model, T_map_obj, plane.normal, plane.height).first);
}

std::vector<FeatureContact> inferRelations(const std::vector<PosedModel>& objects,
                                           const PosedModel* ground, const Eigen::Vector3d& gravity,
                                           const ContactConfig& config,
                                           const std::vector<ObjectPair>& held) {
  std::vector<PosedModel> all;
  const int offset = ground ? 1 : 0;
  if (ground) all.push_back(*ground);
  all.insert(all.end(), objects.begin(), objects.end());
  std::vector<ObjectPair> held_all;
  for (const ObjectPair& p : held) {
    if ((p.first < 0 || p.second < 0) && !ground) continue;
    held_all.emplace_back(std::min(p.first, p.second) + offset,
                          std::max(p.first, p.second) + offset);
  }
  std::vector<FeatureContact> out = findAllContacts(all, gravity, config, held_all);
  for (FeatureContact& c : out) c.object_a -= offset, c.object_b -= offset;
  return out;
}

}  // namespace geofusion
