// Physically settled clutter scenes (Bullet) checked with FCL, and their contact graphs.
#include "geofusion/simulation/clutter_scene.h"
#include "geofusion/simulation/dataset.h"

#include "test_data.h"

#include <gtest/gtest.h>

#include <set>

namespace geofusion {
namespace {

// Every object rests on something: the table or another object within touching distance below.
void expectNothingFloats(const ClutterScene& scene, const ClutterConfig& config) {
  const int n = static_cast<int>(scene.objects.size());
  for (int i = 0; i < n; ++i) {
    bool resting = hullDistance(scene, -1, i) <= config.touch_distance_m;
    for (int j = 0; j < n && !resting; ++j) {
      if (j != i && hullDistance(scene, i, j) <= config.touch_distance_m &&
          scene.objects[j].T_world_obj.translation().z() <
              scene.objects[i].T_world_obj.translation().z())
        resting = true;
    }
    if (resting) continue;
    // What is nearest, to tell a float from a lean on something taller.
    int nearest = -1;
    double gap = hullDistance(scene, -1, i);
    for (int j = 0; j < n; ++j) {
      if (j != i && hullDistance(scene, i, j) < gap) gap = hullDistance(scene, i, j), nearest = j;
    }
    ADD_FAILURE() << scene.objects[i].model->name << " #" << i << " floats: nearest "
                  << (nearest < 0 ? std::string("table") : scene.objects[nearest].model->name)
                  << " #" << nearest << " " << 1000 * gap << " mm away, centres at z "
                  << scene.objects[i].T_world_obj.translation().z() << " and "
                  << (nearest < 0 ? 0.0 : scene.objects[nearest].T_world_obj.translation().z());
  }
}

TEST(ClutterScene, PrimitivesSettleWithoutInterpenetrationAndWithAContactGraph) {
  const ModelSet models = ModelSet::builtinPrimitives();
  ClutterConfig config;
  config.num_objects = 14;
  ClutterScene scene;
  std::string report;
  ASSERT_TRUE(makeClutterScene(models, config, 11, &scene, &report)) << report;
  EXPECT_EQ(scene.objects.size(), 14u);
  EXPECT_LE(scene.max_penetration_m, 0.001) << report;
  expectNothingFloats(scene, config);
  for (const auto& o : scene.objects) {
    const Eigen::Vector3d p = o.T_world_obj.translation();
    EXPECT_GT(p.z(), scene.table.height_m);
    EXPECT_LT(std::abs(p.x()), 0.5 * scene.table.size_x_m);
  }
  // The table supports a bottom layer; some object rests on another; every contact involves
  // a touching pair.
  int on_table = 0, stacked = 0, side = 0;
  for (const auto& c : scene.contacts) {
    EXPECT_LE(hullDistance(scene, c.object_a, c.object_b), config.touch_distance_m);
    if (c.support() && c.object_a == -1) ++on_table;
    if (c.support() && c.object_a >= 0) ++stacked;
    if (!c.support()) ++side;
  }
  EXPECT_GE(on_table, 6) << report;
  EXPECT_GE(stacked, 1) << report;
  std::cout << report << "; " << on_table << " on the table, " << stacked << " stacked, " << side
            << " side contacts\n";

  // Deterministic from the seed.
  ClutterScene again;
  ASSERT_TRUE(makeClutterScene(models, config, 11, &again, &report));
  ASSERT_EQ(again.objects.size(), scene.objects.size());
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    EXPECT_TRUE(again.objects[i].T_world_obj.isApprox(scene.objects[i].T_world_obj, 1e-9));
  }
}

TEST(ClutterScene, FclFindsInterpenetrationAndDistance) {
  const ModelSet models = ModelSet::builtinPrimitives();
  ClutterScene scene;
  const auto box = models.models()[1];  // cracker box 0.072 x 0.164 x 0.213
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() =
      Eigen::Vector3d(0, 0, scene.table.height_m + 0.1065 - 0.003);  // 3 mm into the table
  scene.objects.push_back({box, T});
  std::pair<int, int> pair;
  EXPECT_NEAR(maxPenetration(scene, &pair), 0.003, 0.0005);
  EXPECT_EQ(pair, std::make_pair(-1, 0));
  T.translation().z() += 0.013;  // now 1 cm above
  scene.objects[0].T_world_obj = T;
  EXPECT_EQ(maxPenetration(scene), 0.0);
  EXPECT_NEAR(hullDistance(scene, -1, 0), 0.01, 0.0005);
}

TEST(ClutterScene, YcbSceneOfEighteenObjects) {
  if (!test::haveYcb()) GTEST_SKIP() << "YCB-Video models not found at " << test::ycbDir();
  ModelSet models;
  std::vector<std::string> errors;
  ASSERT_TRUE(test::loadYcbModels(&models, &errors));
  // Made the way every data set makes its scenes (makeSuiteScene: seed 5, and the next seeds
  // when a settled scene breaks the penetration bound). Bullet settles the same seed differently
  // with another compiler: with GCC 14 (Debian 13) seed 5 rests two objects 1.6 mm into each
  // other and the second seed is taken.
  SuiteSpec suite;
  SceneSpec spec;
  spec.seed = 5;
  spec.num_objects = 18;
  const ClutterConfig& config = suite.clutter;
  ClutterScene scene;
  std::string report;
  unsigned seed = 0;
  ASSERT_TRUE(makeSuiteScene(suite, spec, models, &scene, &seed, &report, 3)) << report;
  EXPECT_LE(scene.max_penetration_m, config.max_penetration_m);
  EXPECT_EQ(scene.objects.size(), 18u);
  expectNothingFloats(scene, config);
  std::set<std::string> classes;
  for (const auto& o : scene.objects) classes.insert(o.model->name);
  EXPECT_GE(classes.size(), 8u);
  std::cout << "seed " << seed << ": " << scene.objects.size() << " objects, deepest "
            << scene.max_penetration_m * 1000.0 << " mm\n";
}

}  // namespace
}  // namespace geofusion
