// Bringing one's own meshes in (model/model_import.h, tool make_model_set): units, watertightness,
// symmetry found numerically (on primitives and on the YCB-Video scans against the shipped
// declarations), the YAML written and read back, and the tool end to end.
#include "geofusion/model/model_import.h"
#include "test_data.h"

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace geofusion {
namespace {

namespace fs = std::filesystem;

Symmetry rotations(std::vector<std::pair<Eigen::Vector3d, double>> axis_angles_deg) {
  Symmetry s;
  s.type = Symmetry::Type::kDiscrete;
  for (const auto& [axis, deg] : axis_angles_deg)
    s.rotations.emplace_back(Eigen::AngleAxisd(deg * M_PI / 180.0, axis.normalized()));
  return s;
}

// The mesh as a plain OBJ (vertices and triangles).
void writeObj(const TriangleMesh& mesh, const std::string& path) {
  std::ofstream obj(path);
  for (const auto& v : mesh.vertices) obj << "v " << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (const auto& t : mesh.triangles)
    obj << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
}

TEST(ModelImport, UnitsAreReadFromTheSize) {
  TriangleMesh box = makeBox({0.2, 0.1, 0.05});
  UnitsCheck units = checkUnits(box);
  EXPECT_EQ(units.scale, 1.0);
  EXPECT_TRUE(units.message.empty()) << units.message;
  scaleMesh(1000.0, &box);  // the same box in millimetres
  units = checkUnits(box);
  EXPECT_EQ(units.scale, 1e-3);
  EXPECT_NE(units.message.find("read as millimetres"), std::string::npos) << units.message;
  scaleMesh(1e-6, &box);  // 0.2 mm: not a tabletop object in metres
  units = checkUnits(box);
  EXPECT_EQ(units.scale, 1.0);
  EXPECT_NE(units.message.find("check the file's units"), std::string::npos) << units.message;
}

TEST(ModelImport, HolesAndNonManifoldEdgesAreCounted) {
  TriangleMesh box = makeBox({0.2, 0.1, 0.05});  // faces with their own vertices (seams)
  WatertightCheck closed = checkWatertight(box);
  EXPECT_TRUE(closed.watertight());
  EXPECT_EQ(closed.edges, 18u);  // 12 box edges and 6 face diagonals
  box.triangles.pop_back();      // a hole: the open triangle's 3 edges are used once
  closed = checkWatertight(box);
  EXPECT_FALSE(closed.watertight());
  EXPECT_EQ(closed.boundary_edges, 3u);
  TriangleMesh fin = makeBox({0.2, 0.1, 0.05});
  fin.triangles.push_back(fin.triangles.front());  // a third triangle on two of its edges
  EXPECT_EQ(checkWatertight(fin).non_manifold_edges, 3u);
}

TEST(ModelImport, WindingIsChecked) {
  TriangleMesh box = makeBox({0.2, 0.1, 0.05});
  WatertightCheck check = checkWatertight(box);
  EXPECT_EQ(check.misoriented_edges, 0u);
  EXPECT_NEAR(check.signed_volume_m3, 0.2 * 0.1 * 0.05, 1e-9);
  EXPECT_TRUE(check.closedOutward());
  std::swap(box.triangles[0][1], box.triangles[0][2]);  // one triangle wound the other way
  check = checkWatertight(box);
  EXPECT_TRUE(check.watertight());
  EXPECT_EQ(check.misoriented_edges, 3u);
  EXPECT_FALSE(check.closedOutward());
  for (auto& t : box.triangles) std::swap(t[1], t[2]);  // all the other way: wound inward
  check = checkWatertight(box);
  EXPECT_EQ(check.misoriented_edges, 3u);
  std::swap(box.triangles[0][1], box.triangles[0][2]);
  check = checkWatertight(box);
  EXPECT_EQ(check.misoriented_edges, 0u);
  EXPECT_NEAR(check.signed_volume_m3, -0.2 * 0.1 * 0.05, 1e-9);
  EXPECT_FALSE(check.closedOutward());
  const TriangleMesh cylinder = makeCylinder(0.04, 0.1, 24);
  EXPECT_TRUE(checkWatertight(cylinder).closedOutward());
}

TEST(ModelImport, PrimitivesShowTheirSymmetry) {
  const auto box = detectSymmetry(makeBox({0.2, 0.1, 0.05}));
  EXPECT_TRUE(sameSymmetry(
      box.symmetry, rotations({{Eigen::Vector3d::UnitX(), 180}, {Eigen::Vector3d::UnitY(), 180}})))
      << describe(box.symmetry);
  const auto prism = detectSymmetry(makeBox({0.06, 0.06, 0.2}));
  EXPECT_TRUE(sameSymmetry(
      prism.symmetry, rotations({{Eigen::Vector3d::UnitZ(), 90}, {Eigen::Vector3d::UnitX(), 180}})))
      << describe(prism.symmetry);
  const auto cylinder = detectSymmetry(makeCylinder(0.03, 0.1));
  EXPECT_EQ(cylinder.symmetry.type, Symmetry::Type::kContinuous);
  EXPECT_NEAR(std::abs(cylinder.symmetry.axis.z()), 1.0, 1e-9);
  EXPECT_LT(cylinder.axis_offset_m, 1e-6);

  // A wedge (a box with one corner cut off) has none; a box moved off its origin keeps its
  // symmetry about its centre, and says how far that is from the origin.
  TriangleMesh wedge = makeBox({0.2, 0.1, 0.05});
  for (auto& v : wedge.vertices)
    if (v.x() > 0 && v.y() > 0 && v.z() > 0) v = Eigen::Vector3f(0.02f, 0.01f, 0.0f);
  EXPECT_EQ(detectSymmetry(wedge).symmetry.type, Symmetry::Type::kNone)
      << describe(detectSymmetry(wedge).symmetry);
  TriangleMesh moved = makeBox({0.2, 0.1, 0.05});
  for (auto& v : moved.vertices) v += Eigen::Vector3f(0.0f, 0.0f, 0.03f);
  const auto off = detectSymmetry(moved);
  EXPECT_EQ(off.symmetry.type, Symmetry::Type::kDiscrete);
  EXPECT_NEAR(off.axis_offset_m, 0.03, 1e-4);
}

TEST(ModelImport, SameSymmetryComparesTheGroups) {
  const Symmetry d4 = rotations({{Eigen::Vector3d::UnitZ(), 90},
                                 {Eigen::Vector3d::UnitZ(), 180},
                                 {Eigen::Vector3d::UnitZ(), 270},
                                 {Eigen::Vector3d::UnitX(), 180},
                                 {Eigen::Vector3d::UnitY(), 180}});
  EXPECT_TRUE(sameSymmetry(
      d4, rotations({{Eigen::Vector3d::UnitZ(), -90}, {Eigen::Vector3d(1, 1, 0), 180}})));
  EXPECT_FALSE(sameSymmetry(
      d4, rotations({{Eigen::Vector3d::UnitZ(), 180}, {Eigen::Vector3d::UnitX(), 180}})));
  Symmetry z, minus_z, x;
  z.type = minus_z.type = x.type = Symmetry::Type::kContinuous;
  minus_z.axis = -Eigen::Vector3d::UnitZ();
  x.axis = Eigen::Vector3d::UnitX();
  EXPECT_TRUE(sameSymmetry(z, minus_z));
  EXPECT_FALSE(sameSymmetry(z, x));
  EXPECT_FALSE(sameSymmetry(z, d4));
}

TEST(ModelImport, WrittenYamlReadsBack) {
  const std::string dir = testing::TempDir() + "/geofusion_model_import";
  fs::create_directories(dir);
  ModelSetEntry box;
  box.name = "my_box";
  box.id = 7;
  box.mesh = "box.obj";
  box.scale = 0.001;
  box.symmetry = rotations({{Eigen::Vector3d::UnitZ(), 90}, {Eigen::Vector3d::UnitX(), 180}});
  box.features = extractSurfaceFeatures(makeBox({0.06, 0.06, 0.2}));
  box.notes = {"a note"};
  writeObj(makeBox({60, 60, 200}), dir + "/box.obj");  // the box in millimetres
  std::ofstream(dir + "/set.yaml") << modelSetYaml("mine", {box});
  ModelSet set;
  std::vector<std::string> errors;
  ASSERT_TRUE(ModelSet::load(dir + "/set.yaml", "", &set, &errors));
  ASSERT_TRUE(errors.empty()) << errors.front();
  const ObjectModel* m = set.find("my_box");
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->id, 7);
  EXPECT_NEAR(m->extents.z(), 0.2, 1e-6);  // scale: 0.001 applied
  EXPECT_TRUE(sameSymmetry(m->symmetry, box.symmetry)) << describe(m->symmetry);
  EXPECT_EQ(m->features.planes.size(), box.features.planes.size());
  EXPECT_EQ(m->features.curves.size(), box.features.curves.size());
}

// The YCB-Video scans: every symmetry the shipped model set declares is found, and no other;
// millimetre copies are recognised, rescaled, and give the same.
TEST(ModelImport, YcbVideoSymmetriesMatchTheShippedDeclarations) {
  if (!test::haveYcb()) GTEST_SKIP() << "YCB-Video models not found in " << test::ycbDir();
  ModelSet declared;
  std::vector<std::string> errors;
  ASSERT_TRUE(test::loadYcbModels(&declared, &errors));
  ASSERT_EQ(declared.size(), 21u);
  for (const auto& model : declared.models()) {
    const auto found = detectSymmetry(model->mesh);
    EXPECT_TRUE(sameSymmetry(found.symmetry, model->symmetry))
        << model->name << ": declared " << describe(model->symmetry) << ", found "
        << describe(found.symmetry);
    if (model->name == "036_wood_block" || model->name == "061_foam_brick") {
      TriangleMesh mm = model->mesh;
      scaleMesh(1000.0, &mm);
      const UnitsCheck units = checkUnits(mm);
      EXPECT_EQ(units.scale, 1e-3) << model->name;
      scaleMesh(units.scale, &mm);
      EXPECT_TRUE(sameSymmetry(detectSymmetry(mm).symmetry, model->symmetry)) << model->name;
    }
  }
}

// make_model_set on a folder: a millimetre mesh is rescaled with a warning, the YAML loads with
// the symmetries found, previews are written, a corrupt mesh stops it unless --skip-bad.
TEST(ModelImport, ToolWritesALoadableModelSet) {
  const std::string dir = testing::TempDir() + "/geofusion_make_model_set";
  fs::remove_all(dir);
  fs::create_directories(dir + "/meshes/can");
  writeObj(makeBox({60, 60, 200}), dir + "/meshes/block_mm.obj");
  writeObj(makeCylinder(0.03, 0.1), dir + "/meshes/can/can.obj");
  const std::string tool = MAKE_MODEL_SET;
  const std::string run = tool + " --meshes " + dir + "/meshes --out " + dir + "/set.yaml" +
                          " --previews " + dir + "/previews > " + dir + "/log 2>&1";
  ASSERT_EQ(std::system(run.c_str()), 0) << std::ifstream(dir + "/log").rdbuf();
  std::stringstream log;
  log << std::ifstream(dir + "/log").rdbuf();
  EXPECT_NE(log.str().find("block_mm: largest extent 200 is more than 2 m: read as millimetres"),
            std::string::npos)
      << log.str();
  ModelSet set;
  std::vector<std::string> errors;
  ASSERT_TRUE(ModelSet::load(dir + "/set.yaml", dir + "/meshes", &set, &errors));
  ASSERT_TRUE(errors.empty()) << errors.front();
  ASSERT_EQ(set.size(), 2u);
  EXPECT_EQ(set.find("block_mm")->id, 1);
  EXPECT_NEAR(set.find("block_mm")->extents.z(), 0.2, 1e-6);
  EXPECT_TRUE(
      sameSymmetry(set.find("block_mm")->symmetry,
                   rotations({{Eigen::Vector3d::UnitZ(), 90}, {Eigen::Vector3d::UnitX(), 180}})));
  EXPECT_EQ(set.find("can")->symmetry.type, Symmetry::Type::kContinuous);
  EXPECT_GT(fs::file_size(dir + "/previews/can.png"), 1000u);
  EXPECT_GT(fs::file_size(dir + "/previews/block_mm.png"), 1000u);

  std::ofstream(dir + "/meshes/broken.stl") << "solid broken\n facet normal 0 0\n";
  fs::remove(dir + "/set.yaml");
  const std::string again =
      tool + " --meshes " + dir + "/meshes --out " + dir + "/set.yaml > " + dir + "/log 2>&1";
  EXPECT_NE(std::system(again.c_str()), 0);
  EXPECT_FALSE(fs::exists(dir + "/set.yaml"));
  const std::string skip =
      again.substr(0, again.find(" > ")) + " --skip-bad > " + dir + "/log 2>&1";
  EXPECT_NE(std::system(skip.c_str()), 0);  // written, but the failure is still the exit code
  EXPECT_TRUE(fs::exists(dir + "/set.yaml"));
}

// make_model_set on millimetre copies of YCB-Video scans (vertices x 1000, texture and material
// beside them): it warns, writes scale 0.001, and the symmetries are the declared ones.
TEST(ModelImport, ToolRescalesMillimetreScans) {
  if (!test::haveYcb()) GTEST_SKIP() << "YCB-Video models not found in " << test::ycbDir();
  const std::string dir = testing::TempDir() + "/geofusion_make_model_set_mm";
  fs::remove_all(dir);
  const std::vector<std::string> names = {"036_wood_block", "061_foam_brick", "007_tuna_fish_can"};
  for (const auto& name : names) {
    const std::string from = test::ycbDir() + "/" + name, to = dir + "/meshes/" + name;
    fs::create_directories(to);
    fs::copy_file(from + "/textured.mtl", to + "/textured.mtl");
    fs::copy_file(from + "/texture_map.jpg", to + "/texture_map.jpg");
    std::ifstream in(from + "/textured.obj");
    std::ofstream out(to + "/textured.obj");
    std::string line;
    while (std::getline(in, line)) {
      if (line.rfind("v ", 0) == 0) {
        std::istringstream v(line.substr(2));
        double x, y, z;
        v >> x >> y >> z;
        out << "v " << 1000 * x << " " << 1000 * y << " " << 1000 * z << "\n";
      } else {
        out << line << "\n";
      }
    }
  }
  const std::string run = std::string(MAKE_MODEL_SET) + " --meshes " + dir + "/meshes --out " +
                          dir + "/set.yaml > " + dir + "/log 2>&1";
  ASSERT_EQ(std::system(run.c_str()), 0) << std::ifstream(dir + "/log").rdbuf();
  std::stringstream log;
  log << std::ifstream(dir + "/log").rdbuf();
  ModelSet declared, made;
  std::vector<std::string> errors;
  ASSERT_TRUE(test::loadYcbModels(&declared, &errors));
  ASSERT_TRUE(ModelSet::load(dir + "/set.yaml", dir + "/meshes", &made, &errors));
  for (const auto& name : names) {
    EXPECT_NE(log.str().find(name + ": largest extent"), std::string::npos) << log.str();
    const ObjectModel* m = made.find(name);
    ASSERT_NE(m, nullptr) << name;
    EXPECT_NEAR(m->extents.maxCoeff(), declared.find(name)->extents.maxCoeff(), 1e-5) << name;
    EXPECT_TRUE(sameSymmetry(m->symmetry, declared.find(name)->symmetry))
        << name << ": " << describe(m->symmetry);
  }
}

}  // namespace
}  // namespace geofusion
