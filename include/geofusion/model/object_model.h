// Object models and model sets: class, mesh, evaluation points, symmetry and surface features.
#pragma once

#include "geofusion/model/mesh.h"
#include "geofusion/model/surface_features.h"

#include <Eigen/Geometry>

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace geofusion {

struct Symmetry {
  enum class Type { kNone, kDiscrete, kContinuous };
  Type type = Type::kNone;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< kContinuous: unit axis, model frame
  std::vector<Eigen::Quaterniond> rotations;        ///< kDiscrete: non-identity symmetries
};

/// How many of `symmetry`'s rotations (identity included) turn about `axis` (either direction,
/// within 3 degrees): 1 for none, 2 for a single 180-degree turn about it; 0 for a continuous
/// symmetry about it (every angle).
int orderAbout(const Symmetry& symmetry, const Eigen::Vector3d& axis);

/// What a depth camera's light does on the object's surface (the sensor models of the data
/// generator; the estimator does not use it): diffuse returns it, dark absorbs it, specular
/// mirrors it away, transparent lets it through.
enum class SurfaceMaterial { kDiffuse, kDark, kSpecular, kTransparent };
const char* toString(SurfaceMaterial material);
bool parseSurfaceMaterial(const std::string& name, SurfaceMaterial* material);

struct ObjectModel {
  std::string name;                                      ///< class label, e.g. "003_cracker_box"
  int id = -1;                                           ///< class id
  SurfaceMaterial material = SurfaceMaterial::kDiffuse;  ///< model-set key `material`
  TriangleMesh mesh;
  std::string mesh_path;                ///< file the mesh came from; empty for primitives
  std::vector<Eigen::Vector3f> points;  ///< evaluation points (ADD/ADD-S), model frame
  /// The shape's symmetries: the rotations the depth (and the collision shape) cannot tell apart.
  Symmetry symmetry;
  /// The appearance's: the rotations a detector that sees the texture cannot tell apart (BOP's
  /// models_info.json symmetries; model-set key `appearance_symmetry`, default `symmetry`). A can
  /// is continuous in shape and none (tuna fish) or 180 degrees (master chef) in appearance: the
  /// estimator then takes the angle about its axis from the detections where they agree, and the
  /// evaluation's BOP metrics score with these.
  Symmetry appearance_symmetry;
  /// Where BOP's model frame has its origin, in this model's frame: BOP's YCB-Video models are
  /// the YCB-Video meshes with the origin moved to the centre of their bounding box, and BOP's
  /// poses are of that frame (T_cam_bop = T_cam_obj x Translation(bop_origin)). Model-set key
  /// `bop_origin`: [x, y, z] in metres, or `box_centre` (of the evaluation points when given,
  /// else of the mesh); default the model's own origin.
  Eigen::Vector3d bop_origin = Eigen::Vector3d::Zero();
  SurfaceFeatures features;
  Eigen::Vector3f extents = Eigen::Vector3f::Zero();  ///< axis-aligned size, metres
  /// The mesh's axis-aligned box, model frame (ModelSet::add fills it; empty: boxOf measures the
  /// mesh).
  Eigen::AlignedBox3f box;
  /// Convex collision hull (collisionHull): the shape physics (Bullet) and collision checks (FCL)
  /// use.
  TriangleMesh collision_hull;
  /// Convex parts whose union covers the shape (collisionParts): what a merge's interpenetration
  /// is measured on. One part, the collision hull, for a model its hull fits.
  std::vector<TriangleMesh> collision_parts;
};

/// The model's axis-aligned box in the model frame: the stored one, or the mesh's when none is
/// stored (a model built by hand).
Eigen::AlignedBox3f boxOf(const ObjectModel& model);

/// The convex collision hull ObjectModel::collision_hull holds: the hull of the <= 400-triangle,
/// <= 2 mm simplification of the mesh (meshoptimizer 0.16 and later), else of the mesh itself cut
/// down to its support points along 400 directions (without meshoptimizer, or 0.15).
TriangleMesh collisionHull(const TriangleMesh& mesh);

/// A convex decomposition of a concave model, made once per model (ModelSet::add): the surface
/// (the vertices of the mesh collisionHull starts from and 3000 samples of it) is cut in two
/// across its longest principal axis, each half's hull kept, and each half cut again while the
/// halves' hulls fill less than `fill` of their parent's volume, to at most 2^max_depth parts
/// (halves overlap by 1 mm so that their union covers the surface). A model its hull fits (a box, a
/// can) keeps one part: `hull` itself.
std::vector<TriangleMesh> collisionParts(const TriangleMesh& mesh, const TriangleMesh& hull,
                                         int max_depth = 3, double fill = 0.95);

class ModelSet {
 public:
  /// The package's own primitive models: boxes and cylinders with the sizes of common YCB
  /// objects, named like them (003_cracker_box, 005_tomato_soup_can, ...), no files needed.
  static ModelSet builtinPrimitives();

  /// Loads a model set YAML (format in docs/model_sets.md). Relative mesh and points paths are
  /// resolved against `models_dir` (empty: the YAML's folder). Classes whose files are missing or
  /// corrupt are left out and each gives one message in `errors` naming the file; the rest load.
  /// Returns false only when the YAML itself cannot be read or parsed.
  static bool load(const std::string& yaml_path, const std::string& models_dir, ModelSet* set,
                   std::vector<std::string>* errors, const SurfaceFeatureConfig& features = {});

  const ObjectModel* find(const std::string& name) const;
  const ObjectModel* findById(int id) const;
  const std::vector<std::shared_ptr<const ObjectModel>>& models() const { return models_; }
  std::size_t size() const { return models_.size(); }
  const std::string& name() const { return name_; }

  /// Adds a model, filling extents, evaluation points (sampled when empty) and surface features
  /// (extracted when empty).
  void add(ObjectModel model, const SurfaceFeatureConfig& feature_config = {});

 private:
  std::string name_;
  std::vector<std::shared_ptr<const ObjectModel>> models_;
  std::map<std::string, std::size_t> by_name_;
};

/// The model-set table, the names every entry point knows: "primitives" (built in),
/// "ycb_video" (<package_dir>/config/models/ycb_video.yaml, meshes from the given folder or
/// $GEOFUSION_YCB_DIR), or the path of a model-set YAML (.yaml / .yml).
const std::vector<std::string>& modelSetNames();

/// Loads the model set `name` of the table (models_dir: its meshes, "" for the default), with
/// `features` for the surface features of meshes that do not list theirs. False with the reasons
/// in `errors` for a name the table does not know, a file that does not load or a set with no
/// loadable class; classes that fail alone are reported in `errors` and left out.
bool loadModelSet(const std::string& name, const std::string& models_dir,
                  const std::string& package_dir, ModelSet* models,
                  std::vector<std::string>* errors, const SurfaceFeatureConfig& features = {});

}  // namespace geofusion
