// The map exported to simulators (physics/scene_export.h): the SDF read by libsdformat, the URDF
// by urdfdom's check_urdf, the meshes by assimp, and the SDF loaded back into the stability check
// gives the same motions to 0.1 mm.
#include "geofusion/model/object_model.h"
#include "geofusion/physics/rigid_world.h"
#include "geofusion/physics/scene_export.h"

#include "test_geometry.h"

#include <gtest/gtest.h>
#if GEOFUSION_HAVE_SDFORMAT
#include <sdf/sdf.hh>
#endif

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>

namespace geofusion {
namespace {

using physics::StabilityBody;
using physics::StabilityConfig;
using physics::StabilityPlane;
using test::at;
using test::rot;

std::string tempFolder() {
  char name[] = "/tmp/geofusion_export_XXXXXX";
  const char* made = mkdtemp(name);
  return made ? std::string(made) : std::string();
}

/// A scene with every case: a box lying on the table, a can standing on it, a can leaning too far
/// (it falls), a box tilted on the plane (it topples), on a plane that is not horizontal in the
/// map frame (a map whose z is not up).
struct Scene {
  ModelSet models = ModelSet::builtinPrimitives();
  std::vector<StabilityBody> bodies;
  StabilityPlane plane;
  Eigen::Vector3d gravity;
  Eigen::Isometry3d T_map_table = Eigen::Isometry3d::Identity();

  Scene() {
    T_map_table.linear() = rot(7, Eigen::Vector3d(1, 2, 0));
    T_map_table.translation() = Eigen::Vector3d(0.4, -0.2, 0.75);
    plane.normal = T_map_table.linear().col(2);
    plane.offset = plane.normal.dot(T_map_table.translation());
    gravity = -plane.normal;
    const auto model = [&](const char* name) {
      return std::shared_ptr<const ObjectModel>(models.models()[index(name)]);
    };
    const auto cracker = model("003_cracker_box"), can = model("005_tomato_soup_can"),
               sugar = model("004_sugar_box");
    const double box_half = 0.5 * cracker->extents.minCoeff();
    // The cracker box lies on its widest face: its thinnest extent along the table's normal.
    int thin = 0;
    cracker->extents.minCoeff(&thin);
    Eigen::Matrix3d lying = Eigen::Matrix3d::Identity();
    if (thin != 2) lying = rot(90, thin == 0 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX());
    bodies.push_back({1, cracker, T_map_table * at(0, 0, box_half, lying)});
    const double can_half = 0.5 * can->extents.z(), can_radius = 0.5 * can->extents.x();
    bodies.push_back({2, can, T_map_table * at(0.02, 0.01, 2 * box_half + can_half)});
    const double lean = 40 * M_PI / 180;  // its lowest rim point 2 mm above the table
    bodies.push_back(
        {3, can,
         T_map_table * at(0.30, 0.0,
                          can_half * std::cos(lean) + can_radius * std::sin(lean) + 0.002,
                          rot(40, Eigen::Vector3d::UnitX()))});
    const Eigen::Matrix3d tilt = rot(30, Eigen::Vector3d::UnitY());
    const Eigen::Vector3d edge =
        tilt * Eigen::Vector3d(0.5 * sugar->extents.x(), 0, -0.5 * sugar->extents.z());
    bodies.push_back(
        {4, sugar,
         T_map_table * at(-0.3, 0, 0) * Eigen::Translation3d(-edge) * Eigen::Isometry3d(tilt)});
  }
  std::size_t index(const std::string& name) const {
    for (std::size_t i = 0; i < models.models().size(); ++i)
      if (models.models()[i]->name == name) return i;
    ADD_FAILURE() << name << " is not a primitive";
    return 0;
  }
};

#if GEOFUSION_HAVE_SDFORMAT
// ignition::math's pose (libsdformat 9 to 12) or gz::math's (13 and later).
template <class Pose>
Eigen::Isometry3d fromSdf(const Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(p.Pos().X(), p.Pos().Y(), p.Pos().Z());
  T.linear() = Eigen::Quaterniond(p.Rot().W(), p.Rot().X(), p.Rot().Y(), p.Rot().Z())
                   .normalized()
                   .toRotationMatrix();
  return T;
}

std::string fileName(const std::string& uri) {
  return uri.substr(uri.find_last_of('/') + 1);
}

/// The exported world read back with libsdformat: its bodies (models found by their visual mesh's
/// file name, "<class>.stl"), its plane (the static box's top face) and its gravity.
struct LoadedScene {
  std::vector<StabilityBody> bodies;
  StabilityPlane plane;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
  std::map<std::string, double> mass;  // by model name
  std::map<std::string, int> collisions;
};

void loadExported(const std::string& path, const ModelSet& models, LoadedScene* out) {
  sdf::Root root;
  const sdf::Errors errors = root.Load(path);
  for (const sdf::Error& e : errors) ADD_FAILURE() << "libsdformat: " << e.Message();
  ASSERT_TRUE(errors.empty());
  ASSERT_EQ(root.WorldCount(), 1u);
  const sdf::World* world = root.WorldByIndex(0);
  const auto g = world->Gravity();
  out->gravity = Eigen::Vector3d(g.X(), g.Y(), g.Z());
  for (uint64_t i = 0; i < world->ModelCount(); ++i) {
    const sdf::Model* model = world->ModelByIndex(i);
    ASSERT_EQ(model->LinkCount(), 1u) << model->Name();
    const sdf::Link* link = model->LinkByIndex(0);
    const Eigen::Isometry3d T = fromSdf(model->RawPose());
    if (model->Static()) {
      ASSERT_EQ(model->Name(), "support_plane");
      ASSERT_EQ(link->CollisionCount(), 1u);
      const sdf::Geometry* geom = link->CollisionByIndex(0)->Geom();
      ASSERT_EQ(geom->Type(), sdf::GeometryType::BOX);
      const double thickness = geom->BoxShape()->Size().Z();
      out->plane.normal = T.linear().col(2);
      out->plane.offset = out->plane.normal.dot(T.translation()) + 0.5 * thickness;
      continue;
    }
    ASSERT_EQ(link->VisualCount(), 1u);
    const std::string visual = fileName(link->VisualByIndex(0)->Geom()->MeshShape()->Uri());
    const std::string name = visual.substr(0, visual.size() - 4);  // "<class>.stl"
    const ObjectModel* m = models.find(name);
    ASSERT_NE(m, nullptr) << visual;
    std::shared_ptr<const ObjectModel> shared;
    for (const auto& candidate : models.models())
      if (candidate.get() == m) shared = candidate;
    const int id = std::stoi(model->Name().substr(model->Name().find_last_of('_') + 1));
    out->bodies.push_back({id, shared, T});
    out->mass[model->Name()] = link->Inertial().MassMatrix().Mass();
    out->collisions[model->Name()] = static_cast<int>(link->CollisionCount());
  }
}
#endif

TEST(SceneExport, SdfAndUrdfParseAndTheSdfStandsAsTheMapDoes) {
  const Scene scene;
  StabilityConfig config;
  config.duration_s = 1.0;
  const std::string folder = tempFolder();
  ASSERT_FALSE(folder.empty());
  physics::SceneExport exported;
  std::string error;
  ASSERT_TRUE(physics::exportScene(scene.bodies, &scene.plane, scene.gravity, config, folder,
                                   &exported, &error))
      << error;
  EXPECT_EQ(exported.exported, 4);
  EXPECT_TRUE(exported.warnings.empty()) << exported.warnings.front();
  // Meshes once per class: a visual and the collision hull for each of the three.
  EXPECT_EQ(exported.mesh_paths.size(), 6u);
  for (const std::string& path : exported.mesh_paths) {
    TriangleMesh mesh;
    EXPECT_TRUE(loadMesh(path, &mesh, &error)) << error;
  }

  // urdfdom's own checker (Debian's liburdfdom-tools) parses the URDF.
  const std::string check =
      std::string(CHECK_URDF) + " " + exported.urdf_path + " > " + folder + "/check_urdf.txt 2>&1";
  EXPECT_EQ(std::system(check.c_str()), 0) << "check_urdf failed: see " << folder;
  std::ifstream report(folder + "/check_urdf.txt");
  const std::string text((std::istreambuf_iterator<char>(report)),
                         std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("root Link: map has 5 child(ren)"), std::string::npos) << text;

#if !GEOFUSION_HAVE_SDFORMAT
  GTEST_SKIP() << "built without libsdformat (Debian 13 packages none): the SDF is not read back";
#else
  LoadedScene loaded;
  loadExported(exported.sdf_path, scene.models, &loaded);
  ASSERT_EQ(loaded.bodies.size(), scene.bodies.size());
  EXPECT_NEAR((loaded.gravity - 9.81 * scene.gravity).norm(), 0.0, 1e-6);
  EXPECT_NEAR((loaded.plane.normal - scene.plane.normal).norm(), 0.0, 1e-6);
  EXPECT_NEAR(loaded.plane.offset, scene.plane.offset, 1e-7);
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const StabilityBody& a = scene.bodies[i];
    const StabilityBody& b = loaded.bodies[i];
    const std::string name = physics::exportedBodyName(a);
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.model, b.model) << name;
    EXPECT_LT((a.T_world_obj.translation() - b.T_world_obj.translation()).norm(), 1e-7) << name;
    EXPECT_LT(
        Eigen::AngleAxisd(a.T_world_obj.linear().transpose() * b.T_world_obj.linear()).angle(),
        1e-6)
        << name;
    const auto shapes = physics::bodyShapes(*a.model, config);
    EXPECT_EQ(loaded.collisions[name], static_cast<int>(shapes.size())) << name;
    EXPECT_NEAR(loaded.mass[name],
                physics::compoundMassProperties(shapes, config.density_kg_m3).mass_kg, 1e-6)
        << name;
  }

  // The round trip: the same motions to 0.1 mm, and some of them are not small.
  const auto before = physics::checkStability(scene.bodies, &scene.plane, scene.gravity, config);
  const auto after = physics::checkStability(loaded.bodies, &loaded.plane, loaded.gravity, config);
  ASSERT_EQ(before.bodies.size(), after.bodies.size());
  EXPECT_EQ(before.stable, 2) << "the box and the can on it stand, the leaning can and the tilted "
                                 "box fall";
  for (std::size_t i = 0; i < before.bodies.size(); ++i) {
    EXPECT_NEAR(before.bodies[i].translation_m, after.bodies[i].translation_m, 1e-4)
        << before.bodies[i].id;
    EXPECT_EQ(before.bodies[i].stable, after.bodies[i].stable) << before.bodies[i].id;
  }
  EXPECT_GT(before.max_translation_m, 0.02);
#endif
}

TEST(SceneExport, BadInputIsNamedAndTheRestIsWritten) {
  Scene scene;
  scene.bodies.push_back({7, nullptr, at(0, 0, 0)});
  Eigen::Isometry3d nan_pose = at(0, 0, 0);
  nan_pose.translation().x() = std::nan("");
  scene.bodies.push_back({8, scene.bodies[0].model, nan_pose});
  ObjectModel empty;
  empty.name = "no shape";
  scene.bodies.push_back({9, std::make_shared<const ObjectModel>(empty), at(0, 0, 0)});
  StabilityConfig config;
  config.friction = -1;
  const std::string folder = tempFolder() + "/nested/folder";
  physics::SceneExport exported;
  std::string error;
  // No plane: a floor under the lowest object, said.
  ASSERT_TRUE(
      physics::exportScene(scene.bodies, nullptr, scene.gravity, config, folder, &exported, &error))
      << error;
  EXPECT_EQ(exported.exported, 4);
  std::string all;
  for (const std::string& w : exported.warnings) all += w + "\n";
  for (const char* expected :
       {"physics.friction = -1 is out of range", "object_7: no model",
        "003_cracker_box_8: pose not finite", "no_shape_9: no collision shape", "no support plane"})
    EXPECT_NE(all.find(expected), std::string::npos) << expected << " not in\n" << all;
#if GEOFUSION_HAVE_SDFORMAT
  LoadedScene loaded;
  loadExported(exported.sdf_path, scene.models, &loaded);
  EXPECT_EQ(loaded.bodies.size(), 4u);
#endif

  // A folder that cannot be made: false, and the reason.
  EXPECT_FALSE(physics::exportScene(scene.bodies, &scene.plane, scene.gravity, StabilityConfig(),
                                    exported.sdf_path + "/inside_a_file", &exported, &error));
  EXPECT_NE(error.find("cannot make the folder"), std::string::npos) << error;
}

}  // namespace
}  // namespace geofusion
