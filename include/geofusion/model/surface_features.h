// Geometric surface features of an object model (paper: "Geometric Surface Feature"): plane
// features (centre C_p, outward normal N_p, boundary points B_p) and curved features (centre C_c,
// axis N_c, two boundary points on the axis B_c, radius r; polyhedron edges have r = 0).
// All in the model frame, metres.
#pragma once

#include "geofusion/model/mesh.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace geofusion {

struct PlaneFeature {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, pointing out of the object
  std::vector<Eigen::Vector3d> boundary;              ///< convex polygon, in order
  double area_m2 = 0.0;
};

struct CurvedFeature {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< unit
  Eigen::Vector3d end_a = Eigen::Vector3d::Zero();  ///< boundary points on the axis
  Eigen::Vector3d end_b = Eigen::Vector3d::Zero();
  double radius_m = 0.0;  ///< 0 for an edge of a polyhedron
  double length() const { return (end_b - end_a).norm(); }
};

struct SurfaceFeatures {
  std::vector<PlaneFeature> planes;
  std::vector<CurvedFeature> curves;
};

struct SurfaceFeatureConfig {
  /// Hull facets whose normals are within this angle of a plane's seed facet join the plane.
  double plane_angle_tolerance_deg = 6.0;
  /// ... and whose centres are within this distance of the seed's plane, metres.
  double plane_distance_tolerance_m = 0.004;
  /// A plane must cover at least this share of the hull's area ...
  double min_plane_area_fraction = 0.05;
  /// ... and be at least this wide in its narrowest in-plane direction, metres.
  double min_plane_width_m = 0.01;
  /// Edges shorter than this are dropped, metres.
  double min_edge_length_m = 0.01;
  /// Hull vertices within this distance of both planes lie on their common edge, metres.
  double edge_distance_tolerance_m = 0.004;
  /// Planes whose normals differ by less than this angle do not form an edge.
  double min_edge_angle_deg = 30.0;
  /// A cylinder side: the non-plane facets cover at least this share of the hull's area, ...
  double min_curved_area_fraction = 0.3;
  /// ... at least this share of that area has normals within curved_normal_tolerance_deg of
  /// perpendicular to the axis (rims and lips may slant), ...
  double min_side_share = 0.8;
  double curved_normal_tolerance_deg = 15.0;
  /// ... and the spread (std / mean) of their vertices' distance to the axis is below this.
  double max_radius_spread = 0.12;
};

/// Features extracted from the model's convex hull (qhull through PCL): coplanar hull facets are
/// merged into plane features; two opposite planes whose remaining facets wrap around their
/// common axis make a cylinder side (a curved feature); pairs of non-parallel planes meeting along
/// a line make zero-radius edges.
SurfaceFeatures extractSurfaceFeatures(const std::vector<Eigen::Vector3f>& points,
                                       const SurfaceFeatureConfig& config = {});
SurfaceFeatures extractSurfaceFeatures(const TriangleMesh& mesh,
                                       const SurfaceFeatureConfig& config = {});

/// e.g. "6 planes, 12 curves (12 edges)".
std::string describe(const SurfaceFeatures& features);

}  // namespace geofusion
