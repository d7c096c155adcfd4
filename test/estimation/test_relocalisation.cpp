// Relocalisation on a revisit (issue 22): the detections of a table seen again through a drifted
// camera are brought back onto the map's objects, and the estimator keeps its objects instead of
// mapping the table a second time beside itself.
#include "geofusion/estimation/relocalisation.h"
#include "geofusion/estimation/scene_estimator.h"

#include "table_scene.h"

#include <gtest/gtest.h>

#include <random>

namespace geofusion {
namespace {

// A tabletop of 14 objects (some classes twice), 1.2 x 0.8 m.
std::vector<LabelledPoint> tabletop(std::mt19937& rng) {
  const char* classes[] = {"mug", "can", "box", "bowl", "drill", "clamp", "can"};
  std::uniform_real_distribution<double> x(-0.6, 0.6), y(-0.4, 0.4);
  std::vector<LabelledPoint> out;
  for (int i = 0; i < 14; ++i)
    out.push_back({classes[i % 7], Eigen::Vector3d(x(rng), y(rng), 0.8)});
  return out;
}

Eigen::Isometry3d headingShift(double deg, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).matrix();
  T.translation() = t;
  return T;
}

TEST(Relocalisation, DriftedDetectionsAreBroughtBackOntoTheMap) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.004);
  const std::vector<LabelledPoint> map = tabletop(rng);
  // The drive back drifted: 4 degrees of heading and 12 cm (the camera sees the table through
  // the drift, so its detections land at drift x truth).
  const Eigen::Isometry3d drift = headingShift(4.0, Eigen::Vector3d(0.12, -0.05, 0.01));
  std::vector<LabelledPoint> detections;
  for (std::size_t i = 0; i < map.size(); ++i) {
    if (i % 5 == 4) continue;  // missed
    Eigen::Vector3d p = drift * map[i].position;
    p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    detections.push_back({map[i].class_name, p});
  }
  detections.push_back({"mug", drift * Eigen::Vector3d(0.3, 0.1, 0.85)});  // phantoms
  detections.push_back({"box", drift * Eigen::Vector3d(-0.2, -0.3, 0.8)});
  const Relocalisation r = relocalise(detections, map, -Eigen::Vector3d::UnitZ(), {});
  EXPECT_TRUE(r.tried);
  ASSERT_TRUE(r.applied);
  EXPECT_LE(r.inliers_before, 2);
  EXPECT_GE(r.inliers_after, 10);
  const Eigen::Isometry3d error = r.T_correction * drift;  // identity when exact
  EXPECT_LT(error.translation().norm(), 0.01);
  EXPECT_LT(Eigen::AngleAxisd(error.linear()).angle(), 0.3 * M_PI / 180.0);

  // The same table 20 m from the map's origin: the correction's translation there is large
  // (a heading turn about the origin), what it moves the detections by is not.
  std::vector<LabelledPoint> far_map = map, far_detections;
  const Eigen::Isometry3d far = headingShift(0.0, Eigen::Vector3d(20.0, 5.0, 0.0));
  for (LabelledPoint& p : far_map) p.position = far * p.position;
  const Eigen::Isometry3d far_drift = far * drift * far.inverse();
  for (const LabelledPoint& d : detections)
    far_detections.push_back({d.class_name, far_drift * far * drift.inverse() * d.position});
  const Relocalisation far_r = relocalise(far_detections, far_map, -Eigen::Vector3d::UnitZ(), {});
  ASSERT_TRUE(far_r.applied);
  EXPECT_GT(far_r.T_correction.translation().norm(), 1.0);
  const Eigen::Vector3d table = far * Eigen::Vector3d(0, 0, 0.8);  // undone where it matters
  EXPECT_LT((far_r.T_correction * far_drift * table - table).norm(), 0.01);

  // Without drift nothing is searched; a table of other objects is not matched.
  std::vector<LabelledPoint> on_map;
  for (const LabelledPoint& p : map) on_map.push_back(p);
  EXPECT_FALSE(relocalise(on_map, map, -Eigen::Vector3d::UnitZ(), {}).tried);
  std::mt19937 other_rng(99);
  const Relocalisation other = relocalise(tabletop(other_rng), map, -Eigen::Vector3d::UnitZ(), {});
  EXPECT_TRUE(other.tried);
  EXPECT_FALSE(other.applied) << other.inliers_after << " detections matched";
}

// The estimator on a table it saw, then the same table through odometry that drifted during a
// drive: relocalised, the same objects are measured again; not, the table is mapped again.
TEST(Relocalisation, ARevisitMeasuresTheMappedObjects) {
  const ModelSet models = ModelSet::builtinPrimitives();
  test::TableScene scene(models);
  const char* names[] = {"003_cracker_box", "005_tomato_soup_can",
                         "061_foam_brick",  "004_sugar_box",
                         "025_mug",         "008_pudding_box"};
  const double xy[][2] = {{-0.14, 0.05}, {0.02, 0.15},   {0.13, -0.04},
                          {0.16, 0.12},  {-0.05, -0.08}, {-0.18, -0.12}};
  for (int i = 0; i < 6; ++i) scene.place(names[i], xy[i][0], xy[i][1], 0.3 * i);
  scene.renderObserved();
  auto run = [&](bool relocalise_on, int* relocalised) {
    EstimatorConfig config;
    config.relocalisation.enabled = relocalise_on;
    SceneEstimator estimator(models, config, test::sharedRenderer());
    KeyframeResult r;
    *relocalised = 0;
    for (int t = 0; t < 24; ++t) {
      // From keyframe 12 on, the odometry is off by the drift of a drive.
      const Eigen::Isometry3d drift =
          t < 12 ? Eigen::Isometry3d::Identity() : headingShift(5.0, Eigen::Vector3d(0.1, 0.06, 0));
      r = estimator.addKeyframe(scene.keyframe(t, {0, 1, 2, 3, 4, 5}, drift));
      *relocalised += r.relocalisation.applied;
    }
    return r;
  };
  // Objects of the map within 1 cm of a true object of their class (the map frame is the world:
  // the odometry was right before the drive).
  auto in_place = [&](const KeyframeResult& r) {
    int n = 0;
    for (const ObjectEstimate& o : r.objects) {
      for (int i = 0; i < 6; ++i) {
        if (scene.object(i).model->name == o.model->name &&
            (o.T_map_obj.translation() - scene.object(i).T_world_obj.translation()).norm() < 0.01)
          ++n;
      }
    }
    return n;
  };
  int relocalised = 0;
  const KeyframeResult with = run(true, &relocalised);
  EXPECT_EQ(relocalised, 1);
  EXPECT_EQ(with.objects.size(), 6u);
  EXPECT_EQ(in_place(with), 6);
  EXPECT_NEAR(with.T_map_cam.translation().x(), scene.T_world_cam().translation().x(), 0.01);
  EXPECT_NEAR(with.T_map_cam.translation().y(), scene.T_world_cam().translation().y(), 0.01);
  // Without, the map follows the drift (the drifted copies replace the mapped objects).
  const KeyframeResult without = run(false, &relocalised);
  EXPECT_EQ(relocalised, 0);
  EXPECT_LT(in_place(without), 3);
}

}  // namespace
}  // namespace geofusion
