// Geometric relations of the estimated scene (paper, "Object Geometric Relationship Inference"):
// the supporting plane (the table) estimated from depth with PCL's RANSAC plane segmentation and
// kept as a grounded object with a fixed plane feature, and the contacts between the map's
// objects and with it (the shared findContacts).
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/estimation/contacts.h"
#include "geofusion/model/object_model.h"
#include "geofusion/render/consistency.h"

#include <Eigen/Geometry>

#include <memory>
#include <utility>
#include <vector>

namespace geofusion {

struct SupportPlaneConfig {
  int pixel_stride = 4;                ///< use every n-th row and column of the depth image
  double max_range_m = 2.5;            ///< ignore farther points
  double distance_threshold_m = 0.01;  ///< RANSAC inlier distance
  int max_iterations = 200;
  double max_tilt_deg = 15.0;  ///< the plane normal within this angle of -gravity
  int min_inliers = 800;       ///< fewer: no plane this keyframe
  /// Once a plane is known it is followed (a least-squares refit near it) and searched for
  /// again (RANSAC, the dominant plane, fused or not by fuseSupportPlane) every n-th keyframe,
  /// so that a better supported surface can still take over; 1 = searched every keyframe.
  int search_every_n_keyframes = 10;
  double thickness_m = 0.03;  ///< the grounded object: a slab this thick under the plane
};

/// A horizontal supporting plane in the map frame.
struct SupportPlane {
  bool valid = false;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< up, against gravity
  double height = 0.0;  ///< signed distance of the plane from the map origin along normal
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();    ///< centre of the inliers' extent
  Eigen::Vector2d size = Eigen::Vector2d::Zero();      ///< extent of the inliers in the plane
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  ///< columns: in-plane x, y, normal
  int inliers = 0;                                     ///< summed over the fused estimates
  int observations = 0;                                ///< keyframes fused
};

/// The dominant plane within max_tilt of horizontal among the keyframe's depth points (in the map
/// frame through T_map_cam), by PCL SACSegmentation (RANSAC). With a `known` valid plane (the
/// fused one of earlier keyframes) it is followed instead: the least-squares plane through the
/// points near it, by PCL's plane model, when they are at least min_inliers and at least half as
/// many as the known plane had a keyframe on average (RANSAC otherwise, e.g. at another table).
/// Invalid when there is none.
SupportPlane estimateSupportPlane(const DepthImageView& depth, const PinholeIntrinsics& K,
                                  const Eigen::Isometry3d& T_map_cam,
                                  const Eigen::Vector3d& gravity,
                                  const SupportPlaneConfig& config = SupportPlaneConfig(),
                                  const SupportPlane* known = nullptr);

/// Fuses a new estimate into a running one (inlier-weighted height, union of the extents). An
/// estimate more than `max_height_difference_m` away is another surface: it replaces the fused
/// one only when it has more than twice its inliers.
void fuseSupportPlane(const SupportPlane& observed, SupportPlane* fused,
                      double max_height_difference_m = 0.03);

/// The grounded object of a plane: a slab (box model) whose top face is the plane; its model
/// frame at the slab centre (returned pose).
std::shared_ptr<ObjectModel> supportPlaneModel(const SupportPlane& plane,
                                               Eigen::Isometry3d* T_map_model,
                                               double thickness_m = 0.03);

/// Signed heights above a plane (unit normal, offset: n.x = height on it) of the lowest and the
/// highest vertex of a posed model's collision hull (its mesh when it has none); the lowest
/// vertex itself (map frame) in `lowest_point` when given.
std::pair<double, double> hullHeightsAbove(const ObjectModel& model,
                                           const Eigen::Isometry3d& T_map_obj,
                                           const Eigen::Vector3d& normal, double height,
                                           Eigen::Vector3d* lowest_point = nullptr);

/// How far an object reaches through the plane, metres (0 when it does not): the depth of its
/// collision hull's lowest vertex below the plane, for an object whose centre lies over the
/// plane's extent (a margin of `margin_m` around it); 0 for anything beside it.
double depthThroughPlane(const SupportPlane& plane, const ObjectModel& model,
                         const Eigen::Isometry3d& T_map_obj, double margin_m = 0.05);

/// Contacts among posed objects and, when `ground` is given, with it (object index -1); the
/// pairs in `held` (the same indices; in contact at the previous keyframe) with the hysteresis
/// thresholds.
std::vector<FeatureContact> inferRelations(const std::vector<PosedModel>& objects,
                                           const PosedModel* ground, const Eigen::Vector3d& gravity,
                                           const ContactConfig& config,
                                           const std::vector<ObjectPair>& held = {});

}  // namespace geofusion
