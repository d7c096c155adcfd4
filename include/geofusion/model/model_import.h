// Bringing one's own meshes into a model set (the make_model_set tool): the checks a mesh needs
// before it can stand for an object (units, watertightness), its rotational symmetries found
// numerically, and the model-set YAML written with them and the surface features
// (docs/model_sets.md).
#pragma once

#include "geofusion/model/object_model.h"

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <vector>

namespace geofusion {

/// What the mesh's size says about its units.
struct UnitsCheck {
  double largest_extent = 0.0;  ///< in the file's units
  double scale = 1.0;           ///< to metres: 1 (metres) or 0.001 (millimetres)
  std::string message;          ///< why it was rescaled or looks wrong; "" when plainly metres
};

/// Metres when the largest extent is at most `max_object_m`; millimetres (scale 0.001) when it is
/// larger and its thousandth is at least `min_object_m`; a message also for objects smaller than
/// `min_object_m` (the file may be in metres of something else).
UnitsCheck checkUnits(const TriangleMesh& mesh, double min_object_m = 0.005,
                      double max_object_m = 2.0);

/// Edges of the mesh after welding vertices at the same position (texture seams split them).
struct WatertightCheck {
  std::size_t edges = 0;
  std::size_t boundary_edges = 0;      ///< used by one triangle: a hole
  std::size_t non_manifold_edges = 0;  ///< used by three or more triangles
  /// Used by two triangles running it the same way: their windings disagree.
  std::size_t misoriented_edges = 0;
  double signed_volume_m3 = 0.0;  ///< positive when the triangles wind counter-clockwise outside
  bool watertight() const { return boundary_edges == 0 && non_manifold_edges == 0; }
  /// Closed, consistently wound, and counter-clockwise seen from outside: its back faces are
  /// never seen from outside, so a renderer may skip them.
  bool closedOutward() const {
    return watertight() && misoriented_edges == 0 && signed_volume_m3 > 0.0;
  }
};
WatertightCheck checkWatertight(const TriangleMesh& mesh);

struct SymmetryDetectionConfig {
  std::size_t samples = 6000;  ///< surface points compared (area-weighted, fixed seed)
  /// A rotation maps the surface onto itself when this quantile of the distances between the
  /// rotated points and the surface ...
  double quantile = 0.9;
  /// ... is below this share of the bounding-box diagonal ...
  double tolerance_fraction = 0.01;
  /// ... or below this distance, metres (scan noise on small objects).
  double min_tolerance_m = 0.002;
  int max_order = 8;  ///< discrete orders tried: 2 .. max_order
  /// Angles (deg) that must all pass for a continuous symmetry (no discrete order up to
  /// max_order divides them all).
  std::vector<double> continuous_angles_deg{23.0, 67.0, 131.0, 157.0};
  /// Textured meshes: a discrete rotation also has to keep the look, at most this share of the
  /// rotated samples changing colour (a printed box's faces tell a detector which way it
  /// lies). Continuous symmetries are geometric only: a label tells a rotation about a can's
  /// axis only coarsely, and depth not at all.
  double max_colour_mismatch = 0.15;
};

/// One rotation tried, with how far it moved the surface off itself.
struct SymmetryTrial {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double angle_deg = 0.0;
  double distance_m = 0.0;  ///< the quantile distance
  double tolerance_m = 0.0;
  /// Textured meshes: share of the rotated samples whose colour differs (a channel by more than
  /// 0.2) from the surface's nearest colour.
  double colour_mismatch = 0.0;
  bool discrete = false;  ///< tried as a discrete rotation: the colour counts
  double max_colour_mismatch = 0.0;
  bool maps_onto_itself() const {
    return distance_m <= tolerance_m && (!discrete || colour_mismatch <= max_colour_mismatch);
  }
};

/// What detectSymmetry found and how.
struct SymmetryDetection {
  Symmetry symmetry;
  /// The point the symmetry axes pass through: the centre of the bounding box, model frame.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  /// How far the axes pass from the model origin, metres. GeoFusion applies symmetries about the
  /// origin: beyond the tolerance, the mesh should be recentred (make_model_set warns).
  double axis_offset_m = 0.0;
  double tolerance_m = 0.0;
  /// Textured meshes: the colour mismatch without rotation (texture detail between samples).
  double colour_baseline = 0.0;
  std::vector<SymmetryTrial> trials;  ///< every rotation tried
};

/// The mesh's symmetries about axes through the centre of its bounding box (directions: the
/// model frame's axes and the well-defined principal axes of its surface): continuous about the
/// first axis where every continuous angle maps the surface onto itself; otherwise discrete with
/// every rotation by a multiple of 360/n about each axis (n the largest order whose rotations map
/// the surface, and on a textured mesh its colours, onto themselves).
SymmetryDetection detectSymmetry(const TriangleMesh& mesh,
                                 const SymmetryDetectionConfig& config = {});

/// True when `a` and `b` are the same symmetry: the same continuous axis (either direction), or
/// the same set of discrete rotations (within `angle_tolerance_deg`).
bool sameSymmetry(const Symmetry& a, const Symmetry& b, double angle_tolerance_deg = 3.0);
/// "none", "continuous about [0, 0, 1]", "discrete: 180 deg about [1, 0, 0], ...".
std::string describe(const Symmetry& symmetry);

/// One class of a model set to write.
struct ModelSetEntry {
  std::string name;
  int id = -1;
  std::string mesh;    ///< path as written (relative to the models folder)
  double scale = 1.0;  ///< written when not 1: the loader scales the mesh to metres
  Symmetry symmetry;
  SurfaceFeatures features;
  std::vector<std::string> notes;  ///< written as comments above the class
};

/// The model-set YAML (docs/model_sets.md) of `entries`, which ModelSet::load reads back.
std::string modelSetYaml(const std::string& set_name, const std::vector<ModelSetEntry>& entries);

}  // namespace geofusion
