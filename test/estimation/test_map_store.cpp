// Saved maps as one unit: round trip, pieces that do not belong together refused, and a save
// killed at every step (a test hook, in a forked child) leaving the old map or the new one whole,
// never a mix, with what the killed save wrote removed by the next load.
#include "geofusion/estimation/map_store.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>

namespace geofusion {
namespace {

namespace fs = std::filesystem;

class MapStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    models = ModelSet::builtinPrimitives();
    dir = fs::temp_directory_path() / ("geofusion_map_store_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    prefix = (dir / "map").string();
  }
  void TearDown() override {
    setSaveMapHook(nullptr);
    fs::remove_all(dir);
  }

  // A map of `n` objects; its background is `n` repeated (a stand-in for the OctoMap bytes).
  RunResults mapOf(int n) const {
    RunResults r;
    r.method = "GeoFusion";
    for (int i = 0; i < n; ++i) {
      ObjectEstimate o;
      o.id = 100 + i;
      o.model = models.models()[static_cast<std::size_t>(i) % models.size()];
      o.T_map_obj.linear() =
          Eigen::AngleAxisd(0.3 + 0.7 * i, Eigen::Vector3d(1.0, 0.5 * i, 2.0).normalized())
              .toRotationMatrix();
      o.T_map_obj.translation() = Eigen::Vector3d(0.1 * i, -0.0123 * i, 0.8 + 0.001 * i);
      o.measurements = 5 + i;
      o.best_consistency = 0.8;
      r.final_map.objects.push_back(o);
    }
    r.T_map_odom.linear() =
        Eigen::AngleAxisd(0.05 * n, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    r.T_map_odom.translation() = Eigen::Vector3d(0.01 * n, 0.0, 0.0);
    return r;
  }
  static BackgroundWriter backgroundOf(int n) {
    return [n](const std::string& path, std::string* error) {
      std::ofstream f(path, std::ios::binary);
      f << std::string(static_cast<std::size_t>(1000 + n), static_cast<char>('a' + n));
      if (!f.good()) *error = "cannot write " + path;
      return f.good();
    };
  }
  std::set<std::string> files() const {
    std::set<std::string> out;
    for (const auto& e : fs::directory_iterator(dir)) out.insert(e.path().filename().string());
    return out;
  }
  // The map under `prefix`: its object count, or -1 when it does not load.
  int loadedObjects(std::string* error = nullptr) const {
    RunResults r;
    MapFiles f;
    std::string e;
    if (!loadMap(prefix, models, &r, &f, &e)) {
      if (error) *error = e;
      return -1;
    }
    // The background is the one written with these objects (n repeated).
    std::ifstream in(f.background, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const int n = static_cast<int>(r.final_map.objects.size());
    EXPECT_EQ(bytes, std::string(static_cast<std::size_t>(1000 + n), static_cast<char>('a' + n)));
    EXPECT_NEAR(r.T_map_odom.translation().x(), 0.01 * n, 1e-12);
    return n;
  }

  ModelSet models;
  fs::path dir;
  std::string prefix;
};

TEST_F(MapStoreTest, SavesAndLoadsObjectsBackgroundAndMapToOdom) {
  MapFiles f;
  std::string error;
  ASSERT_TRUE(saveMap(prefix, mapOf(3), backgroundOf(3), &f, &error)) << error;
  EXPECT_EQ(f.yaml, prefix + ".yaml");
  EXPECT_EQ(files().size(), 2u);
  EXPECT_EQ(loadedObjects(), 3);
  RunResults r;
  ASSERT_TRUE(loadMap(prefix + ".yaml", models, &r, &f, &error)) << error;
  EXPECT_EQ(r.final_map.objects[2].id, 102);
  EXPECT_EQ(r.final_map.objects[2].measurements, 7);
  // Every object comes back with its class and its full pose, and map -> odom with its rotation.
  const RunResults saved = mapOf(3);
  ASSERT_EQ(r.final_map.objects.size(), saved.final_map.objects.size());
  for (std::size_t i = 0; i < saved.final_map.objects.size(); ++i) {
    const ObjectEstimate &a = saved.final_map.objects[i], &b = r.final_map.objects[i];
    EXPECT_EQ(b.id, a.id);
    EXPECT_EQ(b.model, a.model);
    EXPECT_TRUE(b.T_map_obj.isApprox(a.T_map_obj, 1e-9)) << "object " << a.id << ":\n"
                                                         << b.T_map_obj.matrix();
    EXPECT_NEAR(b.best_consistency, a.best_consistency, 1e-9);
  }
  EXPECT_TRUE(r.T_map_odom.isApprox(saved.T_map_odom, 1e-9)) << r.T_map_odom.matrix();
  // A second save replaces the first; the old background goes.
  ASSERT_TRUE(saveMap(prefix, mapOf(5), backgroundOf(5), &f, &error)) << error;
  EXPECT_EQ(files().size(), 2u);
  EXPECT_EQ(loadedObjects(), 5);
}

// Issue 52: what a resume continues from comes back as it was saved: each object's stage I
// history (folded measurements) and the support plane with its extent and evidence; a history
// whose information is not positive definite is refused, naming the object.
TEST_F(MapStoreTest, ObjectHistoriesAndTheSupportPlaneComeBack) {
  RunResults saved = mapOf(2);
  StageOneConfig config;
  for (std::size_t i = 0; i < saved.final_map.objects.size(); ++i) {
    ObjectEstimate& o = saved.final_map.objects[i];
    for (int k = 0; k < 3 + static_cast<int>(i); ++k) {
      Eigen::Isometry3d T_map_cam = Eigen::Isometry3d::Identity();
      T_map_cam.linear() = Eigen::AngleAxisd(0.4 * k, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      T_map_cam.translation() = Eigen::Vector3d(0.3 * k, -0.5, 1.2);
      StageOneMeasurement m;
      m.T_cam_obj = T_map_cam.inverse() * o.T_map_obj;
      m.T_cam_obj.translation().x() += 0.002 * k;  // measurements that disagree a little
      m.ray_sigma_m = k % 2 ? 0.002 : 0.0;
      o.history.add(T_map_cam, m, o.model.get(), o.T_map_obj.linear(), config);
    }
  }
  saved.support_plane.valid = true;
  saved.support_plane.normal = Eigen::Vector3d(0.01, 0.0, 1.0).normalized();
  saved.support_plane.height = 0.75;
  saved.support_plane.centre = Eigen::Vector3d(0.1, 0.2, 0.75);
  saved.support_plane.axes.col(0) = Eigen::Vector3d::UnitY().cross(saved.support_plane.normal);
  saved.support_plane.axes.col(1) =
      saved.support_plane.normal.cross(saved.support_plane.axes.col(0));
  saved.support_plane.axes.col(2) = saved.support_plane.normal;
  saved.support_plane.size = Eigen::Vector2d(1.2, 0.8);
  saved.support_plane.inliers = 31415;
  saved.support_plane.observations = 40;
  MapFiles f;
  std::string error;
  ASSERT_TRUE(saveMap(prefix, saved, backgroundOf(2), &f, &error)) << error;
  RunResults r;
  ASSERT_TRUE(loadMap(prefix, models, &r, &f, &error)) << error;
  for (std::size_t i = 0; i < saved.final_map.objects.size(); ++i) {
    const FoldedMeasurements &a = saved.final_map.objects[i].history,
                             &b = r.final_map.objects[i].history;
    ASSERT_FALSE(b.empty()) << "object " << i;
    EXPECT_EQ(b.count(), a.count());
    EXPECT_TRUE(b.mean().isApprox(a.mean(), 1e-8)) << b.mean().matrix();
    EXPECT_TRUE(b.translationInformation().isApprox(a.translationInformation(), 1e-8));
    EXPECT_NEAR(b.rotationInformation(), a.rotationInformation(), 1e-6 * a.rotationInformation());
  }
  const SupportPlane &a = saved.support_plane, &b = r.support_plane;
  EXPECT_TRUE(b.valid);
  EXPECT_TRUE(b.normal.isApprox(a.normal, 1e-9));
  EXPECT_NEAR(b.height, a.height, 1e-9);
  EXPECT_TRUE(b.centre.isApprox(a.centre, 1e-9));
  EXPECT_TRUE(b.axes.isApprox(a.axes, 1e-8)) << b.axes;
  EXPECT_TRUE(b.size.isApprox(a.size, 1e-9));
  EXPECT_EQ(b.inliers, a.inliers);
  EXPECT_EQ(b.observations, a.observations);

  // A history with a translation information that is not positive definite: refused.
  std::ifstream in(prefix + ".yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t at = text.find("translation_information: [");
  ASSERT_NE(at, std::string::npos) << text;
  text.insert(at + std::string("translation_information: [").size(), "-");
  std::ofstream(prefix + ".yaml") << text;
  EXPECT_FALSE(loadMap(prefix, models, &r, &f, &error));
  EXPECT_NE(error.find("object 100: stage_one_prior"), std::string::npos) << error;
}

TEST_F(MapStoreTest, PiecesThatDoNotBelongTogetherAreRefused) {
  MapFiles f;
  std::string error;
  ASSERT_TRUE(saveMap(prefix, mapOf(2), backgroundOf(2), &f, &error)) << error;
  std::ofstream(f.background, std::ios::binary | std::ios::app) << "x";  // not the one saved
  EXPECT_EQ(loadedObjects(&error), -1);
  EXPECT_NE(error.find("do not belong together"), std::string::npos) << error;
  fs::remove(f.background);
  EXPECT_EQ(loadedObjects(&error), -1);
  EXPECT_NE(error.find("missing"), std::string::npos) << error;
  // A plain results file is not a map.
  RunResults plain = mapOf(1);
  ASSERT_TRUE(writeRunResults(prefix + ".yaml", plain, &error));
  EXPECT_EQ(loadedObjects(&error), -1);
  EXPECT_NE(error.find("not a saved map"), std::string::npos) << error;
}

// A save of 4 objects over a saved map of 2, killed before each of its steps and in the middle of
// writing the background and the YAML: the map loads as the old one or the new one, never mixed.
TEST_F(MapStoreTest, ASaveKilledAtAnyMomentLeavesTheOldOrTheNewMap) {
  for (const std::string kill_at :
       {"background", "in background", "yaml", "in yaml", "cleanup", "never"}) {
    SCOPED_TRACE(kill_at);
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::string error;
    ASSERT_TRUE(saveMap(prefix, mapOf(2), backgroundOf(2), nullptr, &error)) << error;
    auto save = [&] {
      setSaveMapHook([&](const char* step) {
        if (kill_at == step) std::_Exit(9);
      });
      BackgroundWriter writer = backgroundOf(4);
      if (kill_at == "in background") {
        writer = [](const std::string& path, std::string*) {
          std::ofstream(path, std::ios::binary) << "half";
          std::_Exit(9);
          return false;
        };
      }
      RunResults next = mapOf(4);
      if (kill_at == "in yaml") {
        // Dies while the YAML's temporary file is half written.
        setSaveMapHook([&](const char* step) {
          if (std::string(step) == "yaml") {
            std::ofstream(prefix + ".yaml.tmp") << "format: geofusion_res";
            std::_Exit(9);
          }
        });
      }
      saveMap(prefix, next, writer, nullptr, &error);
      std::_Exit(0);
    };
    EXPECT_EXIT(save(), ::testing::ExitedWithCode(kill_at == "never" ? 0 : 9), "");
    const int n = loadedObjects(&error);
    EXPECT_TRUE(n == 2 || n == 4) << error;
    // Killed before the YAML was renamed: the old map; after: the new one.
    const bool committed = kill_at == "cleanup" || kill_at == "never";
    EXPECT_EQ(n, committed ? 4 : 2);
    // The load removed what the killed save left: the YAML and its background only.
    EXPECT_EQ(files().size(), 2u) << ::testing::PrintToString(files());
  }
}

}  // namespace
}  // namespace geofusion
