#include "geofusion/simulation/clutter_scene.h"

#include "geofusion/model/fcl_hull.h"
#include "geofusion/physics/rigid_world.h"

#include <fcl/geometry/shape/box.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <sstream>

namespace geofusion {

ObjectModel TableSpec::model() const {
  ObjectModel m;
  m.name = "table";
  m.id = 0;
  m.mesh = makeBox(Eigen::Vector3d(size_x_m, size_y_m, thickness_m));
  m.extents = m.mesh.extents();
  m.features = extractSurfaceFeatures(m.mesh);
  return m;
}

Eigen::Isometry3d TableSpec::pose() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.0, 0.0, height_m - 0.5 * thickness_m);
  return T;
}

namespace {

struct FclScene {
  std::vector<std::shared_ptr<fcl::CollisionGeometryd>> geometry;  // [0] = table
  std::vector<fcl::CollisionObjectd> objects;
  explicit FclScene(const ClutterScene& s) {
    geometry.push_back(
        std::make_shared<fcl::Boxd>(s.table.size_x_m, s.table.size_y_m, s.table.thickness_m));
    objects.emplace_back(geometry.back(), fcl::Transform3d(s.table.pose().matrix()));
    for (const auto& o : s.objects) {
      geometry.push_back(fclHull(*o.model));
      objects.emplace_back(geometry.back(), fcl::Transform3d(o.T_world_obj.matrix()));
    }
    for (auto& o : objects) o.computeAABB();
  }
  fcl::CollisionObjectd* at(int i) { return &objects[static_cast<std::size_t>(i + 1)]; }
};

// The generator's Bullet world (physics::RigidWorld): the table and the bodies of the objects
// placed so far, each its collision hull with one mass.
class Physics {
 public:
  explicit Physics(const TableSpec& table) : world_(Eigen::Vector3d(0, 0, -9.81)) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(0, 0, table.height_m - 0.5 * table.thickness_m);
    world_.addStaticBox(
        T, Eigen::Vector3d(0.5 * table.size_x_m, 0.5 * table.size_y_m, 0.5 * table.thickness_m),
        0.8, 0.0);
  }

  int add(const ObjectModel& model, const Eigen::Isometry3d& T_world_obj) {
    physics::RigidBodyOptions body;
    body.mass_kg = 0.3;
    body.friction = 0.7;
    body.rolling_friction = 0.002;
    body.linear_damping = 0.2;
    body.angular_damping = 0.4;
    return static_cast<int>(world_.add({collisionHullOf(model)}, T_world_obj, body));
  }

  void remove(int i) { world_.remove(static_cast<std::size_t>(i)); }

  /// Steps until everything rests (or max_s of simulated time).
  void settle(double max_s) {
    const double dt = 1.0 / 240.0;
    int quiet = 0;
    for (double t = 0.0; t < max_s; t += dt) {
      world_.step(dt);
      quiet = world_.moving(0.002, 0.02) ? 0 : quiet + 1;
      if (quiet > 24) break;  // 0.1 s at rest
    }
  }

  Eigen::Isometry3d pose(int i) const { return world_.pose(static_cast<std::size_t>(i)); }
  std::size_t size() const { return world_.size(); }

 private:
  physics::RigidWorld world_;
};

}  // namespace

double maxPenetration(const ClutterScene& scene, std::pair<int, int>* pair) {
  FclScene fcl_scene(scene);
  const int n = static_cast<int>(scene.objects.size());
  double worst = 0.0;
  for (int i = -1; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (!fcl_scene.at(i)->getAABB().overlap(fcl_scene.at(j)->getAABB())) continue;
      const double d = fclPenetration(fcl_scene.at(i), fcl_scene.at(j));
      if (d > worst) {
        worst = d;
        if (pair) *pair = {i, j};
      }
    }
  }
  return worst;
}

double hullDistance(const ClutterScene& scene, int a, int b) {
  FclScene fcl_scene(scene);
  return fclDistance(fcl_scene.at(a), fcl_scene.at(b));
}

std::vector<FeatureContact> groundTruthContacts(const ClutterScene& scene,
                                                const ClutterConfig& config) {
  const ObjectModel table = scene.table.model();
  std::vector<PosedModel> posed;
  posed.push_back({&table, scene.table.pose()});
  for (const auto& o : scene.objects) posed.push_back({o.model.get(), o.T_world_obj});
  FclScene fcl_scene(scene);
  ContactConfig contact_config;
  contact_config.support_only = false;
  std::vector<FeatureContact> out;
  const int n = static_cast<int>(scene.objects.size());
  for (int i = -1; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      fcl::AABBd box = fcl_scene.at(i)->getAABB();
      box.expand(fcl::Vector3d::Constant(config.touch_distance_m));
      if (!box.overlap(fcl_scene.at(j)->getAABB())) continue;
      if (fclDistance(fcl_scene.at(i), fcl_scene.at(j)) > config.touch_distance_m) continue;
      const auto c = findContacts(posed, i + 1, j + 1, -Eigen::Vector3d::UnitZ(), contact_config);
      out.insert(out.end(), c.begin(), c.end());
    }
  }
  markLeaning(posed, &out);  // on `posed` indices (the table is 0), then back to the scene's
  for (FeatureContact& c : out) c.object_a -= 1, c.object_b -= 1;
  return out;
}

namespace {

// Standing beside object k (drawn by `pick`), its longest side up, tipped 25 degrees towards k
// about a horizontal axis, at a distance where its top reaches over k's side: let go, it comes
// to rest leaning on k.
void leanBeside(const Physics& physics,
                const std::vector<std::shared_ptr<const ObjectModel>>& placed,
                const std::shared_ptr<const ObjectModel>& model, double pick, double bearing,
                Eigen::Matrix3d* R, Eigen::Vector2d* xy) {
  const int k = static_cast<int>(pick * physics.size()) % static_cast<int>(physics.size());
  Eigen::Vector3f lo, hi, klo, khi;
  model->mesh.bounds(&lo, &hi);
  placed[static_cast<std::size_t>(k)]->mesh.bounds(&klo, &khi);
  const Eigen::Vector3f size = hi - lo;
  int longest = 0;
  size.maxCoeff(&longest);
  // The longest model axis to world z.
  Eigen::Matrix3d up = Eigen::Matrix3d::Identity();
  if (longest == 0) up = Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  if (longest == 1) up = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const double phi = 2 * M_PI * bearing;
  const Eigen::Vector3d towards(-std::cos(phi), -std::sin(phi), 0.0);  // from the new one to k
  const Eigen::Vector3d tip_axis = Eigen::Vector3d::UnitZ().cross(towards);
  *R = Eigen::AngleAxisd(25.0 * M_PI / 180.0, tip_axis) *
       Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitZ()) * up;
  const double k_radius = 0.5 * static_cast<double>((khi - klo).head<2>().norm());
  const double own = 0.5 * static_cast<double>(size.minCoeff());
  *xy = physics.pose(k).translation().head<2>() - towards.head<2>() * (k_radius + own + 0.01);
}

}  // namespace

bool makeClutterScene(const ModelSet& models, const ClutterConfig& config, unsigned seed,
                      ClutterScene* scene, std::string* report) {
  std::ostringstream log;
  std::vector<std::shared_ptr<const ObjectModel>> pool;
  for (const auto& m : models.models()) {
    if (config.classes.empty() ||
        std::find(config.classes.begin(), config.classes.end(), m->name) != config.classes.end())
      pool.push_back(m);
  }
  if (pool.empty()) {
    if (report) *report = "no models to place (empty model set or no class matches)";
    return false;
  }
  *scene = ClutterScene();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  Physics physics(scene->table);
  std::vector<std::shared_ptr<const ObjectModel>> placed;
  const double top = scene->table.height_m;
  // Anything that left the table top is taken out.
  auto takeOutWhatLeftTheTable = [&]() {
    int taken = 0;
    for (int k = static_cast<int>(physics.size()) - 1; k >= 0; --k) {
      const Eigen::Vector3d p = physics.pose(k).translation();
      if (p.z() < top - 0.02 || std::abs(p.x()) > 0.5 * scene->table.size_x_m ||
          std::abs(p.y()) > 0.5 * scene->table.size_y_m) {
        physics.remove(k);
        placed.erase(placed.begin() + k);
        ++scene->dropped_off_table;
        ++taken;
      }
    }
    return taken;
  };
  int attempts = 0;
  do {
    while (static_cast<int>(placed.size()) < config.num_objects &&
           attempts < 4 * config.num_objects) {
      ++attempts;
      const auto& model = pool[static_cast<std::size_t>(uni(rng) * pool.size()) % pool.size()];
      Eigen::Vector3f lo, hi;
      model->mesh.bounds(&lo, &hi);
      const double radius = 0.5 * static_cast<double>((hi - lo).norm());
      // Orientation: upright or lying on a side, random yaw, a little tilt.
      Eigen::Matrix3d R =
          Eigen::AngleAxisd(2 * M_PI * uni(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      if (uni(rng) < config.lying_fraction) {
        R = R * Eigen::AngleAxisd(
                    M_PI / 2, uni(rng) < 0.5 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY());
      }
      R = Eigen::AngleAxisd(0.1 * (uni(rng) - 0.5), Eigen::Vector3d::UnitX()) * R;
      Eigen::Vector2d xy(config.area_x_m * (uni(rng) - 0.5), config.area_y_m * (uni(rng) - 0.5));
      double floor_z = top;
      const double choice = placed.empty() ? 1.0 : uni(rng);    // no draw for the first
      if (!placed.empty() && choice < config.stack_fraction) {  // onto an existing object
        const int k =
            static_cast<int>(uni(rng) * physics.size()) % static_cast<int>(physics.size());
        xy = physics.pose(k).translation().head<2>() +
             Eigen::Vector2d(0.02 * (uni(rng) - 0.5), 0.02 * (uni(rng) - 0.5));
      } else if (!placed.empty() && choice < config.stack_fraction + config.lean_fraction) {
        leanBeside(physics, placed, model, uni(rng), uni(rng), &R, &xy);
      }
      // Start above everything already within reach of (x, y).
      for (std::size_t k = 0; k < physics.size(); ++k) {
        const Eigen::Vector3d p = physics.pose(static_cast<int>(k)).translation();
        Eigen::Vector3f plo, phi;
        placed[k]->mesh.bounds(&plo, &phi);
        const double r = 0.5 * static_cast<double>((phi - plo).norm());
        if ((p.head<2>() - xy).norm() < r + radius) floor_z = std::max(floor_z, p.z() + r);
      }
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.linear() = R;
      const Eigen::Vector3d centre = (0.5f * (lo + hi)).cast<double>();
      T.translation() = Eigen::Vector3d(xy.x(), xy.y(), floor_z + radius + 0.005) - R * centre;
      physics.add(*model, T);
      placed.push_back(model);
      physics.settle(4.0);
      takeOutWhatLeftTheTable();  // and another object is tried
    }
    physics.settle(3.0);
    // What fell off in the last settling too (seen with GCC 14: a sugar box 28 m below the
    // table), and more objects tried in its place.
  } while (takeOutWhatLeftTheTable() > 0 && attempts < 4 * config.num_objects);
  for (std::size_t k = 0; k < physics.size(); ++k)
    scene->objects.push_back({placed[k], physics.pose(static_cast<int>(k))});
  std::pair<int, int> worst_pair{-2, -2};
  scene->max_penetration_m = maxPenetration(*scene, &worst_pair);
  scene->contacts = groundTruthContacts(*scene, config);
  log << scene->objects.size() << " objects settled (" << scene->dropped_off_table
      << " re-dropped), " << scene->contacts.size() << " contacts, deepest interpenetration "
      << scene->max_penetration_m * 1000.0 << " mm";
  if (scene->max_penetration_m > 0.0)
    log << " (pair " << worst_pair.first << ", " << worst_pair.second << ")";
  if (report) *report = log.str();
  if (static_cast<int>(scene->objects.size()) < config.num_objects) {
    if (report) *report += "; fewer objects than asked";
    return false;
  }
  return scene->max_penetration_m <= config.max_penetration_m;
}

}  // namespace geofusion
