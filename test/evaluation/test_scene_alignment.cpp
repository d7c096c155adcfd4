// alignMapToScene: a table's map found on its scene whatever the drift (the soak benchmark's
// per-table scores, issue 45).
#include "geofusion/evaluation/evaluation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace geofusion {
namespace {

// A settled primitive scene and its objects as a map drifted by T_map_true (plus noise), with
// the first `missing` objects left out and one false object added.
struct DriftedMap {
  ClutterScene scene;
  std::vector<ObjectEstimate> objects;
};

DriftedMap drifted(const ModelSet& models, const Eigen::Isometry3d& T_map_true, int missing,
                   double noise_m) {
  DriftedMap d;
  ClutterConfig config;
  config.num_objects = 14;
  std::string report;
  EXPECT_TRUE(makeClutterScene(models, config, 11, &d.scene, &report)) << report;
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss(0.0, noise_m);
  for (std::size_t i = static_cast<std::size_t>(missing); i < d.scene.objects.size(); ++i) {
    ObjectEstimate e;
    e.model = d.scene.objects[i].model;
    e.T_map_obj = T_map_true * d.scene.objects[i].T_world_obj;
    e.T_map_obj.translation() += Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
    d.objects.push_back(e);
  }
  ObjectEstimate phantom;
  phantom.model = d.scene.objects[0].model;
  phantom.T_map_obj = T_map_true * Eigen::Translation3d(0.9, -0.6, 0.8);
  d.objects.push_back(phantom);
  return d;
}

Eigen::Isometry3d planarDrift(double x, double y, double yaw_deg) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() =
      Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, 0.0);
  return T;
}

TEST(SceneAlignment, FindsATableMetresAndTensOfDegreesOff) {
  const ModelSet models = ModelSet::builtinPrimitives();
  const Eigen::Isometry3d T_map_true = planarDrift(2.3, -1.4, 37.0);
  DriftedMap d = drifted(models, T_map_true, 2, 0.005);
  ASSERT_EQ(d.scene.objects.size(), 14u);
  // Scored where the drift left it, nothing matches.
  EXPECT_EQ(scoreMap(d.scene, d.objects).true_positives, 0);
  const SceneAlignment a = alignMapToScene(d.scene, d.objects);
  EXPECT_EQ(a.inliers, 12);
  EXPECT_LT(a.rmse_m, 0.015);
  // The alignment undoes the drift: the table's centre comes back within 1 cm, the turn within
  // half a degree.
  const Eigen::Isometry3d residual = a.T_true_map * T_map_true;
  EXPECT_LT(residual.translation().norm(), 0.01);
  EXPECT_LT(Eigen::AngleAxisd(residual.linear()).angle(), 0.5 * M_PI / 180.0);
  for (auto& e : d.objects) e.T_map_obj = a.T_true_map * e.T_map_obj;
  const MapScore s = scoreMap(d.scene, d.objects);
  EXPECT_EQ(s.true_positives, 12);
  EXPECT_EQ(s.false_positives, 1);
}

TEST(SceneAlignment, NoDriftStaysNearTheIdentity) {
  const ModelSet models = ModelSet::builtinPrimitives();
  DriftedMap d = drifted(models, Eigen::Isometry3d::Identity(), 0, 0.002);
  const SceneAlignment a = alignMapToScene(d.scene, d.objects);
  EXPECT_EQ(a.inliers, 14);
  EXPECT_LT(a.T_true_map.translation().norm(), 0.01);
}

TEST(SceneAlignment, OneObjectCannotBeAligned) {
  const ModelSet models = ModelSet::builtinPrimitives();
  DriftedMap d = drifted(models, planarDrift(1.0, 0.0, 10.0), 13, 0.0);
  d.objects.pop_back();  // only the last scene object left, no phantom
  ASSERT_EQ(d.objects.size(), 1u);
  const SceneAlignment a = alignMapToScene(d.scene, d.objects);
  EXPECT_EQ(a.inliers, 0);
  EXPECT_TRUE(a.T_true_map.isApprox(Eigen::Isometry3d::Identity()));
}

}  // namespace
}  // namespace geofusion
