#include "geofusion/model/object_model.h"

#include "geofusion/common/enum_names.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cstdlib>
#include <limits>

#include <cmath>

namespace geofusion {

namespace {

constexpr std::size_t kSampledPoints = 2620;  // as many as YCB-Video's evaluation sets

Eigen::Vector3d vec3(const YAML::Node& n, const std::string& what) {
  if (!n.IsSequence() || n.size() != 3) throw std::runtime_error(what + " must be [x, y, z]");
  return Eigen::Vector3d(n[0].as<double>(), n[1].as<double>(), n[2].as<double>());
}

std::string resolve(const std::string& dir, const std::string& path) {
  if (path.empty() || path[0] == '/' || dir.empty()) return path;
  return dir + "/" + path;
}

Symmetry parseSymmetry(const YAML::Node& n) {
  Symmetry s;
  if (!n || (n.IsScalar() && n.as<std::string>() == "none")) return s;
  const std::string type = n["type"].as<std::string>();
  if (type == "continuous") {
    s.type = Symmetry::Type::kContinuous;
    s.axis = vec3(n["axis"], "symmetry axis").normalized();
  } else if (type == "discrete") {
    s.type = Symmetry::Type::kDiscrete;
    // rotations: list of {axis: [x, y, z], angle_deg: a}
    for (const auto& r : n["rotations"]) {
      const Eigen::Vector3d axis = vec3(r["axis"], "rotation axis").normalized();
      s.rotations.emplace_back(Eigen::AngleAxisd(r["angle_deg"].as<double>() * M_PI / 180.0, axis));
    }
  } else if (type != "none") {
    throw std::runtime_error("unknown symmetry type '" + type + "'");
  }
  return s;
}

SurfaceFeatures parseFeatures(const YAML::Node& n) {
  SurfaceFeatures f;
  for (const auto& p : n["planes"]) {
    PlaneFeature plane;
    plane.center = vec3(p["center"], "plane center");
    plane.normal = vec3(p["normal"], "plane normal").normalized();
    for (const auto& b : p["boundary"]) plane.boundary.push_back(vec3(b, "plane boundary point"));
    f.planes.push_back(plane);
  }
  for (const auto& c : n["curves"]) {
    CurvedFeature curve;
    curve.end_a = vec3(c["end_a"], "curve end_a");
    curve.end_b = vec3(c["end_b"], "curve end_b");
    curve.center = 0.5 * (curve.end_a + curve.end_b);
    curve.axis = (curve.end_b - curve.end_a).normalized();
    curve.radius_m = c["radius"].as<double>(0.0);
    f.curves.push_back(curve);
  }
  return f;
}

// `bop_origin`: a point, or "box_centre" (of the evaluation points when loaded, else the mesh).
Eigen::Vector3d parseBopOrigin(const YAML::Node& n, const ObjectModel& m) {
  if (n.IsScalar() && n.as<std::string>() == "box_centre") {
    Eigen::AlignedBox3d box;
    for (const Eigen::Vector3f& p : m.points) box.extend(p.cast<double>());
    if (m.points.empty())
      for (const Eigen::Vector3f& v : m.mesh.vertices) box.extend(v.cast<double>());
    if (box.isEmpty()) throw std::runtime_error("bop_origin: box_centre of an empty model");
    return box.center();
  }
  const Eigen::Vector3d p = vec3(n, "bop_origin");
  if (!p.allFinite()) throw std::runtime_error("bop_origin must be finite");
  return p;
}

Symmetry continuousAboutZ() {
  Symmetry s;
  s.type = Symmetry::Type::kContinuous;
  s.axis = Eigen::Vector3d::UnitZ();
  return s;
}

Symmetry boxSymmetry() {
  // A box with three different edge lengths maps onto itself by 180 degrees about each axis.
  Symmetry s;
  s.type = Symmetry::Type::kDiscrete;
  for (const auto& axis :
       {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()}) {
    s.rotations.emplace_back(Eigen::AngleAxisd(M_PI, axis));
  }
  return s;
}

}  // namespace

int orderAbout(const Symmetry& symmetry, const Eigen::Vector3d& axis) {
  const Eigen::Vector3d a = axis.normalized();
  const double cos_tolerance = std::cos(3.0 * M_PI / 180.0);
  if (symmetry.type == Symmetry::Type::kContinuous)
    return std::abs(symmetry.axis.normalized().dot(a)) >= cos_tolerance ? 0 : 1;
  int n = 1;
  if (symmetry.type != Symmetry::Type::kDiscrete) return n;
  for (const Eigen::Quaterniond& q : symmetry.rotations) {
    const Eigen::AngleAxisd r(q);
    if (r.angle() > 1e-6 && std::abs(r.axis().dot(a)) >= cos_tolerance) ++n;
  }
  return n;
}

namespace {

// The points of `points` furthest along `count` directions spread evenly over the sphere (a
// Fibonacci lattice), each once: their hull has at most `count` vertices and lies inside the
// points' hull, within 2 mm of it on the YCB models (test CollisionHull.*).
std::vector<Eigen::Vector3f> supportPoints(const std::vector<Eigen::Vector3f>& points, int count) {
  std::vector<char> taken(points.size(), 0);
  std::vector<Eigen::Vector3f> out;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / count, r = std::sqrt(1.0 - z * z);
    const Eigen::Vector3f d(float(r * std::cos(golden * i)), float(r * std::sin(golden * i)),
                            float(z));
    std::size_t best = 0;
    for (std::size_t k = 1; k < points.size(); ++k)
      if (points[k].dot(d) > points[best].dot(d)) best = k;
    if (!points.empty() && !taken[best]) {
      taken[best] = 1;
      out.push_back(points[best]);
    }
  }
  return out;
}

}  // namespace

namespace {

// The hull of `points`, cut down to its support points along 400 directions when it has more:
// Bullet's contacts on a hull of thousands of vertices jitter.
TriangleMesh boundedHull(const std::vector<Eigen::Vector3f>& points) {
  constexpr int kDirections = 400;
  TriangleMesh hull = convexHull(points);
  if (hull.vertices.size() > std::size_t(kDirections)) {
    TriangleMesh bounded = convexHull(supportPoints(hull.vertices, kDirections));
    if (!bounded.empty()) hull = std::move(bounded);
  }
  return hull;
}

// The mesh the collision shapes are made from. With meshoptimizer 0.16 or later (error output):
// the <= 400-triangle simplification within 2 mm. Without it (Ubuntu 20.04), or with 0.15
// (Debian 11), which reports no error, so the bound cannot be kept, and whose coarser
// simplification kept only 0.945 of the scissors' hull volume and let a settled YCB scene topple:
// the mesh itself (its hull then bounded to 400 support points by boundedHull). Debian 11 and
// the Ubuntu 20.04 profile thus make the same shapes (docs/platforms.md).
TriangleMesh collisionSource(const TriangleMesh& mesh) {
#if GEOFUSION_HAVE_MESHOPTIMIZER && GEOFUSION_MESHOPT_ERROR_OUTPUT
  return simplifyMesh(mesh, 400, 0.002);
#else
  return mesh;
#endif
}

}  // namespace

TriangleMesh collisionHull(const TriangleMesh& mesh) {
  return boundedHull(collisionSource(mesh).vertices);
}

namespace {

// One cut of collisionParts: `points` split across their longest principal axis at its middle,
// each side with the points within `overlap` of the cut.
void splitAcrossLongestAxis(const std::vector<Eigen::Vector3f>& points, float overlap,
                            std::vector<Eigen::Vector3f>* lower,
                            std::vector<Eigen::Vector3f>* upper) {
  Eigen::Vector3f mean = Eigen::Vector3f::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<float>(points.size());
  Eigen::Matrix3f cov = Eigen::Matrix3f::Zero();
  for (const auto& p : points) cov += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> eig(cov);
  const Eigen::Vector3f axis = eig.eigenvectors().col(2);  // largest eigenvalue last
  float lo = std::numeric_limits<float>::max(), hi = -lo;
  for (const auto& p : points) {
    lo = std::min(lo, axis.dot(p));
    hi = std::max(hi, axis.dot(p));
  }
  const float middle = 0.5f * (lo + hi);
  for (const auto& p : points) {
    const float s = axis.dot(p);
    if (s <= middle + overlap) lower->push_back(p);
    if (s >= middle - overlap) upper->push_back(p);
  }
}

// collisionParts' recursion: `hull` (of `points`) kept, or replaced by its halves' parts.
void addParts(const std::vector<Eigen::Vector3f>& points, TriangleMesh hull, int depth_left,
              double fill, std::vector<TriangleMesh>* parts) {
  const double volume = enclosedVolume(hull);
  if (depth_left > 0 && points.size() >= 40 && volume > 0.0) {
    std::vector<Eigen::Vector3f> lower, upper;
    splitAcrossLongestAxis(points, 0.001f, &lower, &upper);
    TriangleMesh lower_hull = convexHull(lower), upper_hull = convexHull(upper);
    if (!lower_hull.empty() && !upper_hull.empty() &&
        enclosedVolume(lower_hull) + enclosedVolume(upper_hull) < fill * volume) {
      addParts(lower, std::move(lower_hull), depth_left - 1, fill, parts);
      addParts(upper, std::move(upper_hull), depth_left - 1, fill, parts);
      return;
    }
  }
  parts->push_back(std::move(hull));
}

}  // namespace

std::vector<TriangleMesh> collisionParts(const TriangleMesh& mesh, const TriangleMesh& hull,
                                         int max_depth, double fill) {
  if (hull.empty() || mesh.empty()) return {hull};
  const TriangleMesh light = collisionSource(mesh);
  std::vector<Eigen::Vector3f> points = light.vertices;
  const std::vector<Eigen::Vector3f> samples = sampleSurfacePoints(light, 3000, 11);
  points.insert(points.end(), samples.begin(), samples.end());
  // Starting from the collision hull: where it fits, it is the one part (the shape the other
  // checks use).
  std::vector<TriangleMesh> parts;
  addParts(points, hull, max_depth, fill, &parts);
  return parts;
}

Eigen::AlignedBox3f boxOf(const ObjectModel& model) {
  if (!model.box.isEmpty()) return model.box;
  Eigen::Vector3f lo, hi;
  model.mesh.bounds(&lo, &hi);
  return Eigen::AlignedBox3f(lo, hi);
}

void ModelSet::add(ObjectModel model, const SurfaceFeatureConfig& feature_config) {
  model.box.setEmpty();  // measured from the mesh, whatever was stored
  model.box = boxOf(model);
  model.extents =
      model.mesh.vertices.empty() ? Eigen::Vector3f::Zero() : Eigen::Vector3f(model.box.sizes());
  if (model.points.empty()) model.points = sampleSurfacePoints(model.mesh, kSampledPoints);
  if (model.features.planes.empty() && model.features.curves.empty()) {
    model.features = extractSurfaceFeatures(model.mesh, feature_config);
  }
  if (model.collision_hull.empty()) model.collision_hull = collisionHull(model.mesh);
  if (model.collision_parts.empty())
    model.collision_parts = collisionParts(model.mesh, model.collision_hull);
  by_name_[model.name] = models_.size();
  models_.push_back(std::make_shared<const ObjectModel>(std::move(model)));
}

const ObjectModel* ModelSet::find(const std::string& name) const {
  const auto it = by_name_.find(name);
  return it == by_name_.end() ? nullptr : models_[it->second].get();
}

const ObjectModel* ModelSet::findById(int id) const {
  for (const auto& m : models_) {
    if (m->id == id) return m.get();
  }
  return nullptr;
}

namespace {
constexpr std::pair<SurfaceMaterial, const char*> kMaterialNames[] = {
    {SurfaceMaterial::kDiffuse, "diffuse"},
    {SurfaceMaterial::kDark, "dark"},
    {SurfaceMaterial::kSpecular, "specular"},
    {SurfaceMaterial::kTransparent, "transparent"},
};
}  // namespace

const char* toString(SurfaceMaterial material) {
  return nameIn(kMaterialNames, material);
}
bool parseSurfaceMaterial(const std::string& name, SurfaceMaterial* material) {
  return parseIn(kMaterialNames, name, material);
}

ModelSet ModelSet::builtinPrimitives() {
  ModelSet set;
  set.name_ = "primitives";
  auto box = [&set](const char* name, int id, double x, double y, double z) {
    ObjectModel m;
    m.name = name;
    m.id = id;
    m.mesh = makeBox(Eigen::Vector3d(x, y, z));
    m.symmetry = m.appearance_symmetry = boxSymmetry();  // untextured: appearance = shape
    set.add(std::move(m));
  };
  auto cylinder = [&set](const char* name, int id, double diameter, double height) {
    ObjectModel m;
    m.name = name;
    m.id = id;
    m.mesh = makeCylinder(0.5 * diameter, height);
    m.symmetry = m.appearance_symmetry = continuousAboutZ();
    set.add(std::move(m));
  };
  // Sizes measured on the YCB-Video scans (metres; the bounding boxes of their official
  // evaluation points); ids in YCB-Video order.
  cylinder("002_master_chef_can", 1, 0.102, 0.140);
  box("003_cracker_box", 2, 0.072, 0.164, 0.213);
  box("004_sugar_box", 3, 0.049, 0.094, 0.176);
  cylinder("005_tomato_soup_can", 4, 0.067, 0.102);
  cylinder("007_tuna_fish_can", 6, 0.085, 0.034);
  box("008_pudding_box", 7, 0.138, 0.128, 0.039);
  box("009_gelatin_box", 8, 0.089, 0.101, 0.030);
  box("010_potted_meat_can", 9, 0.101, 0.059, 0.083);
  cylinder("025_mug", 14, 0.093, 0.081);  // mug-like: the body without its handle
  box("036_wood_block", 16, 0.090, 0.090, 0.206);
  box("061_foam_brick", 21, 0.052, 0.078, 0.051);
  return set;
}

bool ModelSet::load(const std::string& yaml_path, const std::string& models_dir, ModelSet* set,
                    std::vector<std::string>* errors, const SurfaceFeatureConfig& features) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const std::exception& e) {
    errors->push_back("model set '" + yaml_path + "' cannot be read: " + e.what());
    return false;
  }
  if (!root.IsMap() || !root["classes"] || !root["classes"].IsSequence()) {
    errors->push_back("model set '" + yaml_path + "' has no 'classes' list");
    return false;
  }
  const std::string yaml_dir = yaml_path.substr(0, yaml_path.find_last_of('/'));
  const std::string dir = models_dir.empty() ? yaml_dir : models_dir;
  ModelSet out;
  out.name_ = root["name"].as<std::string>("unnamed");
  for (const auto& c : root["classes"]) {
    std::string name = "<unnamed>";
    try {
      name = c["name"].as<std::string>();
      if (out.find(name)) throw std::runtime_error("class listed twice");
      ObjectModel m;
      m.name = name;
      m.id = c["id"].as<int>();
      std::string error;
      if (c["mesh"]) {
        m.mesh_path = resolve(dir, c["mesh"].as<std::string>());
        if (!loadMesh(m.mesh_path, &m.mesh, &error)) throw std::runtime_error(error);
        if (c["scale"]) {
          const double scale = c["scale"].as<double>();
          if (!(scale > 0.0) || !std::isfinite(scale))
            throw std::runtime_error("scale must be a number above 0");
          scaleMesh(scale, &m.mesh);
        }
      } else if (c["box"]) {
        m.mesh = makeBox(vec3(c["box"], "box size"));
      } else if (c["cylinder"]) {
        m.mesh = makeCylinder(c["cylinder"]["radius"].as<double>(),
                              c["cylinder"]["height"].as<double>());
      } else {
        throw std::runtime_error("needs 'mesh', 'box' or 'cylinder'");
      }
      if (c["points"]) {
        if (!loadPointsXyz(resolve(dir, c["points"].as<std::string>()), &m.points, &error)) {
          throw std::runtime_error(error);
        }
        for (auto& p : m.points) p *= static_cast<float>(c["scale"].as<double>(1.0));
      }
      m.symmetry = parseSymmetry(c["symmetry"]);
      m.appearance_symmetry =
          c["appearance_symmetry"] ? parseSymmetry(c["appearance_symmetry"]) : m.symmetry;
      if (c["bop_origin"]) m.bop_origin = parseBopOrigin(c["bop_origin"], m);
      if (c["material"] && !parseSurfaceMaterial(c["material"].as<std::string>(), &m.material)) {
        throw std::runtime_error("unknown material '" + c["material"].as<std::string>() +
                                 "' (diffuse, dark, specular, transparent)");
      }
      if (c["features"]) m.features = parseFeatures(c["features"]);
      // Contacts, merging, stage II and the physics need a solid: a flat or collinear mesh
      // (a sheet, a box of zero thickness) has no hull.
      m.collision_hull = collisionHull(m.mesh);
      if (m.collision_hull.empty())
        throw std::runtime_error(
            "the mesh has no volume (flat, collinear or empty): no collision hull");
      out.add(std::move(m), features);
    } catch (const std::exception& e) {
      errors->push_back("model set '" + yaml_path + "', class " + name + ": " + e.what() +
                        "; class left out");
    }
  }
  *set = std::move(out);
  return true;
}

const std::vector<std::string>& modelSetNames() {
  static const std::vector<std::string> names{"primitives", "ycb_video"};
  return names;
}

bool loadModelSet(const std::string& name, const std::string& models_dir,
                  const std::string& package_dir, ModelSet* models,
                  std::vector<std::string>* errors, const SurfaceFeatureConfig& features) {
  if (name == "primitives") {
    *models = ModelSet::builtinPrimitives();
    return true;
  }
  std::string path = name, dir = models_dir;
  if (name == "ycb_video") {
    path = package_dir + "/config/models/ycb_video.yaml";
    const char* env = std::getenv("GEOFUSION_YCB_DIR");
    if (dir.empty() && env) dir = env;
    if (dir.empty()) {
      errors->push_back(
          "model set 'ycb_video' needs the folder of the YCB-Video meshes: set model_set.dir "
          "(or $GEOFUSION_YCB_DIR)");
      return false;
    }
  } else {
    const auto ends = [&](const std::string& suffix) {
      return path.size() > suffix.size() &&
             path.compare(path.size() - suffix.size(), suffix.size(), suffix) == 0;
    };
    if (!ends(".yaml") && !ends(".yml")) {
      errors->push_back("unknown model set '" + name +
                        "': expected primitives, ycb_video or the path of a model-set YAML");
      return false;
    }
  }
  if (!ModelSet::load(path, dir, models, errors, features)) return false;
  if (models->size() == 0) {
    errors->push_back("model set '" + name + "' has no loadable class");
    return false;
  }
  return true;
}

}  // namespace geofusion
