// Triangle meshes of object models: primitives the package makes itself, and files loaded with
// assimp (OBJ with texture, PLY, STL). Units: metres, model frame.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace geofusion {

struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Eigen::Vector3i> triangles;  ///< counter-clockwise seen from outside
  std::vector<Eigen::Vector2f> uvs;        ///< per vertex, empty when untextured
  std::string texture_path;                ///< diffuse texture image, empty when none

  bool empty() const { return vertices.empty() || triangles.empty(); }
  double surfaceArea() const;
  /// Axis-aligned bounds in the model frame.
  void bounds(Eigen::Vector3f* min, Eigen::Vector3f* max) const;
  Eigen::Vector3f extents() const;
};

/// Box of full edge lengths `size`, centred at the origin, edges along the axes.
TriangleMesh makeBox(const Eigen::Vector3d& size);
/// Cylinder of `radius` and `height` about the z axis, centred at the origin, `segments` sides.
TriangleMesh makeCylinder(double radius, double height, int segments = 48);

/// Every vertex multiplied by `scale` (units to metres).
void scaleMesh(double scale, TriangleMesh* mesh);
/// Loads a mesh file with assimp (all sub-meshes merged, triangulated). On failure returns false
/// and `error` names the file and the reason (missing, unreadable, no triangles).
bool loadMesh(const std::string& path, TriangleMesh* mesh, std::string* error);
/// Writes the mesh's vertices and triangles with assimp's exporter in `format` (assimp's id:
/// "stlb" binary STL, "obj", "collada", ...). On failure returns false and `error` says why.
bool saveMesh(const std::string& path, const TriangleMesh& mesh, const std::string& format,
              std::string* error);

/// A lighter copy of `mesh` for depth rendering: vertices welded by position (uvs and texture
/// dropped), then edge collapses (meshoptimizer) towards `target_triangles` while the geometric
/// deviation stays below `max_error_m`. `achieved_error_m`, when given, receives meshoptimizer's
/// estimate of the deviation (meshoptimizer 0.15, which gives none: the bound `max_error_m`).
/// Meshes already at or below the target come back welded only. Built without meshoptimizer
/// (Ubuntu 20.04 packages none), every mesh comes back welded only (docs/platforms.md).
TriangleMesh simplifyMesh(const TriangleMesh& mesh, std::size_t target_triangles,
                          double max_error_m, double* achieved_error_m = nullptr);

/// Volume enclosed by a closed mesh with outward triangles (a convex hull's), m^3.
double enclosedVolume(const TriangleMesh& mesh);

/// The points' scatter matrix about their mean (sum of (p - mean)(p - mean)^T), in double: its
/// eigenvectors are their principal axes, its eigenvalues the spread along them.
Eigen::Matrix3d scatterMatrix(const std::vector<Eigen::Vector3f>& points);

/// Convex hull of the points (qhull through PCL), triangles counter-clockwise seen from outside.
/// Empty for fewer than 4 points or degenerate (flat) input.
TriangleMesh convexHull(const std::vector<Eigen::Vector3f>& points);

/// `count` points on the surface, area-weighted, deterministic for a given seed; with `normals`,
/// each point's triangle normal, with `uvs` its interpolated texture coordinates (when the mesh
/// has them).
std::vector<Eigen::Vector3f> sampleSurfacePoints(const TriangleMesh& mesh, std::size_t count,
                                                 std::uint32_t seed = 1,
                                                 std::vector<Eigen::Vector3f>* normals = nullptr,
                                                 std::vector<Eigen::Vector2f>* uvs = nullptr);

/// Reads an "x y z" per line points file (YCB-Video points.xyz). False with `error` on failure.
bool loadPointsXyz(const std::string& path, std::vector<Eigen::Vector3f>* points,
                   std::string* error);

}  // namespace geofusion
