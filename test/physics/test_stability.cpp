// The stability check (physics/stability.h): Bullet under gravity on hand-made scenes whose answer
// is known, and on the generator's settled clutter (primitives, and the YCB meshes when there).
#include "geofusion/physics/stability.h"
#include "geofusion/simulation/clutter_scene.h"

#include "test_data.h"
#include "test_geometry.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

namespace geofusion {
namespace {

using physics::StabilityBody;
using physics::StabilityConfig;
using physics::StabilityPlane;
using test::at;
using test::rot;

std::shared_ptr<const ObjectModel> box(double x, double y, double z) {
  return std::make_shared<const ObjectModel>(test::boxModel(x, y, z));
}

physics::StabilityResult check(const std::vector<StabilityBody>& bodies,
                               const StabilityConfig& config = StabilityConfig()) {
  const StabilityPlane table;  // z = 0, up
  return physics::checkStability(bodies, &table, Eigen::Vector3d(0, 0, -1), config);
}

TEST(Stability, ABoxOnTheTableAndAStackStayPut) {
  const auto b = box(0.10, 0.08, 0.06);
  const auto result =
      check({{1, b, at(0, 0, 0.03)}, {2, b, at(0.3, 0, 0.03)}, {3, b, at(0.3, 0, 0.09)}});
  ASSERT_EQ(result.bodies.size(), 3u);
  EXPECT_TRUE(result.warnings.empty());
  EXPECT_EQ(result.checked, 3);
  EXPECT_EQ(result.stable, 3);
  for (const auto& m : result.bodies) {
    EXPECT_LT(m.translation_m, 0.001) << m.id;
    EXPECT_LT(m.rotation_deg, 0.5) << m.id;
  }
  EXPECT_DOUBLE_EQ(result.stableShare(), 1.0);
}

// Where the bodies came to rest (RestContact): a stack bears on the table with both boxes'
// weight and on the lower box with the upper's; a box 5 mm beside the stack touches nothing.
TEST(Stability, RestContactsBearTheWeightAboveThem) {
  const auto b = box(0.10, 0.08, 0.06);
  StabilityConfig config;
  const auto result = check(
      {{2, b, at(0.3, 0, 0.03)}, {3, b, at(0.3, 0, 0.09)}, {4, b, at(0.405, 0, 0.03)}}, config);
  ASSERT_EQ(result.stable, 3);
  const double weight_N = config.density_kg_m3 * 0.10 * 0.08 * 0.06 * config.gravity_m_s2;
  const auto* table = result.restContact(physics::kPlaneId, 2);
  const auto* stacked = result.restContact(3, 2);  // either order
  ASSERT_TRUE(table && stacked);
  std::printf("normal forces: table %.3f N, stacked %.3f N (one box %.3f N)\n",
              table->normal_force_N, stacked->normal_force_N, weight_N);
  EXPECT_NEAR(table->normal_force_N, 2 * weight_N, 0.1 * weight_N);
  EXPECT_NEAR(stacked->normal_force_N, weight_N, 0.1 * weight_N);
  EXPECT_LT(std::abs(stacked->min_distance_m), 0.001);
  const auto* beside = result.restContact(2, 4);
  EXPECT_TRUE(!beside || beside->min_distance_m > 0.004);
  EXPECT_TRUE(!beside || beside->normal_force_N < 1e-6);
  EXPECT_EQ(result.restContact(3, 4), nullptr);
  EXPECT_NE(result.restContact(physics::kPlaneId, 4), nullptr);
}

TEST(Stability, AFloatingBoxFallsItsGapAndATiltedSlabTopples) {
  const auto b = box(0.10, 0.08, 0.06);
  const auto slab = box(0.02, 0.10, 0.20);
  // The slab stands on one bottom edge, 25 degrees from upright: it falls over.
  const Eigen::Matrix3d tilt = rot(25, Eigen::Vector3d::UnitY());
  const Eigen::Vector3d edge = tilt * Eigen::Vector3d(0.01, 0, -0.10);
  const auto result =
      check({{1, b, at(0, 0, 0.03 + 0.02)},
             {2, slab, at(0.4, 0, 0) * Eigen::Translation3d(-edge) * Eigen::Isometry3d(tilt)}});
  const auto* floating = result.find(1);
  const auto* toppling = result.find(2);
  ASSERT_TRUE(floating && toppling);
  EXPECT_FALSE(floating->stable);
  EXPECT_NEAR(floating->translation_m, 0.02, 0.002);  // it lands and stays on the table
  EXPECT_LT(floating->rotation_deg, 1.0);
  EXPECT_FALSE(toppling->stable);
  EXPECT_GT(toppling->rotation_deg, 30.0);
  EXPECT_EQ(result.stable, 0);
  EXPECT_GT(result.max_translation_m, 0.02);
  // The slab on the table is the only pair in contact at the start.
  EXPECT_EQ(result.least_stable_pair, std::make_pair(2, physics::kPlaneId));
}

TEST(Stability, InterpenetratingObjectsAreReportedApart) {
  const auto b = box(0.10, 0.08, 0.06);
  // Side by side on the table, 5 mm into each other; a third box away from them.
  const auto result =
      check({{1, b, at(0, 0, 0.03)}, {2, b, at(0.095, 0, 0.03)}, {3, b, at(0.5, 0, 0.03)}});
  ASSERT_EQ(result.bodies.size(), 3u);
  EXPECT_TRUE(result.bodies[0].interpenetrating);
  EXPECT_TRUE(result.bodies[1].interpenetrating);
  EXPECT_NEAR(result.bodies[0].start_penetration_m, 0.005, 0.0005);
  EXPECT_EQ(result.bodies[0].penetrating_id, 2);
  EXPECT_FALSE(result.bodies[0].stable);
  EXPECT_EQ(result.interpenetrating, 2);
  EXPECT_EQ(result.checked, 1);
  EXPECT_EQ(result.stable, 1);
  // Sunk 4 mm into the table: apart as well, the plane named.
  const auto sunk = check({{7, b, at(0, 0, 0.026)}});
  EXPECT_TRUE(sunk.bodies[0].interpenetrating);
  EXPECT_EQ(sunk.bodies[0].penetrating_id, physics::kPlaneId);
  EXPECT_NEAR(sunk.bodies[0].start_penetration_m, 0.004, 1e-6);
}

TEST(Stability, BadInputIsNamedAndTheRestStillChecked) {
  const auto b = box(0.10, 0.08, 0.06);
  auto empty = std::make_shared<ObjectModel>();
  empty->name = "no_mesh";
  Eigen::Isometry3d nan_pose = at(0.3, 0, 0.03);
  nan_pose(0, 3) = std::numeric_limits<double>::quiet_NaN();
  StabilityConfig bad;
  bad.density_kg_m3 = -1.0;
  const auto result =
      check({{1, b, at(0, 0, 0.03)}, {2, empty, at(0.2, 0, 0.03)}, {3, b, nan_pose}}, bad);
  ASSERT_EQ(result.bodies.size(), 3u);
  EXPECT_TRUE(test::anyMentions(result.warnings, "physics.density_kg_m3"));
  EXPECT_TRUE(test::anyMentions(result.warnings, "no_mesh"));
  EXPECT_EQ(result.bodies[1].problem, "no collision shape");
  EXPECT_EQ(result.bodies[2].problem, "pose not finite");
  EXPECT_EQ(result.simulated, 1);
  EXPECT_TRUE(result.bodies[0].stable);
  // No support plane: a floor under the lowest object, said.
  const auto floor = physics::checkStability({{1, b, at(0, 0, 0.53)}}, nullptr,
                                             Eigen::Vector3d(0, 0, -1), StabilityConfig());
  EXPECT_FALSE(floor.has_plane);
  EXPECT_TRUE(test::anyMentions(floor.warnings, "no support plane"));
  EXPECT_TRUE(floor.bodies[0].stable);
}

// The generator's settled scenes stand: the reference row of every benchmark.
// `min_share`: the generator stops settling when everything moves slower than 2 mm/s and
// 0.02 rad/s for 0.1 s, so an object leaning on another can still creep a few mm; no object falls.
void expectSettledSceneStands(const ModelSet& models, int objects, unsigned seed, double min_share,
                              const StabilityConfig& check = StabilityConfig()) {
  ClutterConfig config;
  config.num_objects = objects;
  ClutterScene scene;
  std::string report;
  // The next seed when a settled scene breaks the penetration bound, as the data sets do.
  for (int tries = 0; !makeClutterScene(models, config, seed, &scene, &report) && tries < 5;
       ++tries)
    ++seed;
  ASSERT_LE(scene.max_penetration_m, config.max_penetration_m) << report;
  std::vector<StabilityBody> bodies;
  for (std::size_t i = 0; i < scene.objects.size(); ++i)
    bodies.push_back({int(i), scene.objects[i].model, scene.objects[i].T_world_obj});
  const StabilityPlane table{Eigen::Vector3d::UnitZ(), scene.table.height_m};
  const auto result = physics::checkStability(bodies, &table, Eigen::Vector3d(0, 0, -1), check);
  EXPECT_EQ(result.interpenetrating, 0);
  EXPECT_EQ(result.checked, int(scene.objects.size()));
  EXPECT_GE(result.stableShare(), min_share);
  for (const auto& m : result.bodies) {
    // Unstable or not, nothing falls or topples (tens of degrees): a creep of a few mm and a
    // rock of a few degrees at most. Debian 11's coarser hulls (400 support points, no
    // meshoptimizer error bound) rock a banana on its curved side 7.2 degrees; 12's 4.5.
    EXPECT_LT(m.translation_m, 0.01) << scene.objects[m.id].model->name << " #" << m.id;
    EXPECT_LT(m.rotation_deg, 10.0) << scene.objects[m.id].model->name << " #" << m.id;
    if (!m.stable)
      std::cout << "[ stability ] " << scene.objects[m.id].model->name << " #" << m.id << " moves "
                << 1000 * m.translation_m << " mm, " << m.rotation_deg << " deg\n";
  }
  std::cout << "[ stability ] " << models.name() << " seed " << seed << ": " << result.stable
            << " of " << result.checked << " stable, " << 1000 * result.mean_translation_m
            << " mm mean, " << 1000 * result.max_translation_m << " mm max, "
            << result.max_rotation_deg << " deg max\n";
}

TEST(Stability, SettledPrimitiveClutterStands) {
  expectSettledSceneStands(ModelSet::builtinPrimitives(), 14, 11, 1.0);
}

TEST(Stability, SettledYcbClutterStands) {
  if (!test::haveYcb()) GTEST_SKIP() << "no YCB-Video meshes in " << test::ycbDir();
  ModelSet models;
  std::vector<std::string> errors;
  ASSERT_TRUE(test::loadYcbModels(&models, &errors));
  expectSettledSceneStands(models, 16, 5, 0.8);  // 13 of 16 measured (docs/stability.md)
}

}  // namespace
}  // namespace geofusion
