// Relocalisation on a revisit (issue 22): the detections of a table seen again through a drifted
// camera are brought back onto the map's objects, and the estimator keeps its objects instead of
// mapping the table a second time beside itself.
#include "geofusion/estimation/relocalisation.h"
#include "geofusion/estimation/scene_estimator.h"

#include "table_scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
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
  ASSERT_TRUE(r.applied) << toString(r.decision) << ": support " << r.inliers_after
                         << ", runner-up " << r.runner_up;
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
// A keyframe of a drive away from the table: no images, no detections, the odometry reading.
Keyframe driveKeyframe(double stamp, const Eigen::Isometry3d& T_odom_cam,
                       const PinholeIntrinsics& K) {
  Keyframe kf;
  kf.stamp_s = stamp;
  kf.T_odom_cam = T_odom_cam;
  kf.K = K;
  return kf;
}

// Objects of the map within 1 cm of a true object of their class (the map frame is the world:
// the odometry was right before the drive).
int inPlace(const test::TableScene& scene, int n, const KeyframeResult& r) {
  int in_place = 0;
  for (const ObjectEstimate& o : r.objects) {
    for (int i = 0; i < n; ++i) {
      if (scene.object(i).model->name == o.model->name &&
          (o.T_map_obj.translation() - scene.object(i).T_world_obj.translation()).norm() < 0.01)
        ++in_place;
    }
  }
  return in_place;
}

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
  const Eigen::Isometry3d drift = headingShift(5.0, Eigen::Vector3d(0.1, 0.06, 0));
  // 12 keyframes at the table, then (drive > 0) a drive of `drive` keyframes 2 m away and back
  // whose odometry drifts by `drift` on the way, then 12 keyframes at the table again.
  auto run = [&](bool relocalise_on, int drive, std::vector<Relocalisation>* decisions) {
    EstimatorConfig config;
    config.relocalisation.enabled = relocalise_on;
    SceneEstimator estimator(models, config, test::sharedRenderer());
    KeyframeResult r;
    int t = 0;
    for (; t < 12; ++t) r = estimator.addKeyframe(scene.keyframe(t, {0, 1, 2, 3, 4, 5}));
    for (int k = 1; k <= drive; ++k, ++t) {
      const double s = static_cast<double>(k) / drive;  // out and back along -y
      const Eigen::Isometry3d away =
          headingShift(0.0, Eigen::Vector3d(0, -4.0 * std::min(s, 1 - s), 0));
      const Eigen::Isometry3d drifted =
          headingShift(5.0 * s, s * drift.translation()) * away * scene.T_world_cam();
      r = estimator.addKeyframe(driveKeyframe(t, drifted, scene.K()));
    }
    for (int k = 0; k < 12; ++k, ++t) {
      r = estimator.addKeyframe(scene.keyframe(t, {0, 1, 2, 3, 4, 5}, drift));
      if (r.relocalisation.tried) decisions->push_back(r.relocalisation);
    }
    return r;
  };
  auto applied = [](const std::vector<Relocalisation>& d) {
    return std::count_if(d.begin(), d.end(), [](const Relocalisation& r) { return r.applied; });
  };
  std::vector<Relocalisation> decisions;
  const KeyframeResult with = run(true, 40, &decisions);
  EXPECT_EQ(applied(decisions), 1);
  ASSERT_FALSE(decisions.empty());
  EXPECT_GT(decisions.front().drift.path_m, 3.9);  // judged against the drive's drift
  EXPECT_LT(decisions.front().mahalanobis_sq, 18.47);
  EXPECT_EQ(with.objects.size(), 6u);
  EXPECT_EQ(inPlace(scene, 6, with), 6);
  EXPECT_NEAR(with.T_map_cam.translation().x(), scene.T_world_cam().translation().x(), 0.01);
  EXPECT_NEAR(with.T_map_cam.translation().y(), scene.T_world_cam().translation().y(), 0.01);
  // Without, the map follows the drift (the drifted copies replace the mapped objects).
  decisions.clear();
  const KeyframeResult without = run(false, 40, &decisions);
  EXPECT_TRUE(decisions.empty());
  EXPECT_LT(inPlace(scene, 6, without), 3);
  // The same jump with no drive (the odometry cannot have drifted that far while standing at the
  // table): refused as beyond the drift, every time it is searched.
  decisions.clear();
  run(true, 0, &decisions);
  ASSERT_FALSE(decisions.empty());
  EXPECT_EQ(applied(decisions), 0);
  EXPECT_EQ(decisions.front().decision, RelocalisationDecision::kBeyondDrift);
  EXPECT_GT(decisions.front().mahalanobis_sq, 18.47);
}

// A saved map resumed by a robot whose odometry restarted elsewhere: map -> odom as given is off
// by 8 degrees and 25 cm. With no drift known since a restart, the first keyframe is relocalised
// without a gate; the map keeps its objects and ids, and the camera is where it truly is.
TEST(Relocalisation, AResumedMapIsRelocalisedAtItsFirstKeyframe) {
  const ModelSet models = ModelSet::builtinPrimitives();
  test::TableScene scene(models);
  const char* names[] = {"003_cracker_box", "005_tomato_soup_can", "061_foam_brick",
                         "004_sugar_box", "025_mug"};
  const double xy[][2] = {{-0.14, 0.05}, {0.02, 0.15}, {0.13, -0.04}, {0.16, 0.12}, {-0.05, -0.08}};
  for (int i = 0; i < 5; ++i) scene.place(names[i], xy[i][0], xy[i][1], 0.3 * i);
  scene.renderObserved();
  SceneEstimator first(models, EstimatorConfig(), test::sharedRenderer());
  for (int t = 0; t < 12; ++t) first.addKeyframe(scene.keyframe(t, {0, 1, 2, 3, 4}));
  const KeyframeResult saved = first.finish();
  ASSERT_EQ(saved.objects.size(), 5u);
  // After the restart the odometry frame is somewhere else: odom = offset x world.
  const Eigen::Isometry3d offset = headingShift(8.0, Eigen::Vector3d(0.25, -0.1, 0.0));
  SceneEstimator resumed(models, EstimatorConfig(), test::sharedRenderer());
  ASSERT_TRUE(resumed.resume(saved.objects, Eigen::Isometry3d::Identity()));
  KeyframeResult r = resumed.addKeyframe(scene.keyframe(20, {0, 1, 2, 3, 4}, offset));
  EXPECT_TRUE(r.relocalisation.applied) << toString(r.relocalisation.decision);
  EXPECT_FALSE(std::isfinite(r.relocalisation.drift.sigma_m));  // no gate after a restart
  for (int t = 21; t < 26; ++t) r = resumed.addKeyframe(scene.keyframe(t, {0, 1, 2, 3, 4}, offset));
  EXPECT_LT((r.T_map_cam.translation() - scene.T_world_cam().translation()).norm(), 0.01);
  ASSERT_EQ(r.objects.size(), 5u);
  EXPECT_EQ(inPlace(scene, 5, r), 5);
  for (const ObjectEstimate& o : saved.objects) {
    EXPECT_TRUE(std::any_of(r.objects.begin(), r.objects.end(),
                            [&](const ObjectEstimate& x) { return x.id == o.id; }))
        << "object " << o.id << " lost its id";
  }
}

// Two identical groups of four objects side by side (a shelf of repeated products): the group
// seen through a drifted camera matches either group equally well. Refused as ambiguous; with
// the second group gone the same detections are relocalised.
TEST(Relocalisation, AnAmbiguousLayoutIsRefused) {
  const char* classes[] = {"mug", "can", "box", "bowl"};
  const double xy[][2] = {{0.0, 0.0}, {0.12, 0.05}, {0.05, 0.16}, {-0.08, 0.1}};
  std::vector<LabelledPoint> group, map;
  for (int i = 0; i < 4; ++i)
    group.push_back({classes[i], Eigen::Vector3d(xy[i][0], xy[i][1], 0.8)});
  for (const LabelledPoint& p : group) map.push_back(p);
  for (const LabelledPoint& p : group)
    map.push_back({p.class_name, p.position + Eigen::Vector3d(0.3, 0.0, 0.0)});
  const Eigen::Isometry3d drift = headingShift(3.0, Eigen::Vector3d(0.15, 0.0, 0.0));
  std::vector<LabelledPoint> detections;
  for (const LabelledPoint& p : group) detections.push_back({p.class_name, drift * p.position});
  const Relocalisation r = relocalise(detections, map, -Eigen::Vector3d::UnitZ(), {});
  EXPECT_TRUE(r.tried);
  EXPECT_FALSE(r.applied);
  EXPECT_EQ(r.decision, RelocalisationDecision::kAmbiguous);
  EXPECT_EQ(r.inliers_after, 4);
  EXPECT_EQ(r.runner_up, 4);
  map.resize(4);
  const Relocalisation one = relocalise(detections, map, -Eigen::Vector3d::UnitZ(), {});
  ASSERT_TRUE(one.applied) << toString(one.decision);
  EXPECT_LE(one.runner_up, 2);
  EXPECT_LT((one.T_correction * drift).translation().norm(), 0.01);
}

// The drift of a path: the random part per keyframe, the systematic part with the path and the
// turns, heading errors through their lever arm.
TEST(Relocalisation, DriftGrowsWithThePathAndTheLeverArm) {
  RelocalisationConfig config;
  std::vector<Eigen::Isometry3d> standing(11, Eigen::Isometry3d::Identity());
  const Eigen::Vector3d centre(0.0, 0.0, 1.0);
  const OdometryDrift still = accumulatedDrift(standing, centre, config, 0.003, 0.004);
  EXPECT_EQ(still.keyframes, 10);
  EXPECT_DOUBLE_EQ(still.path_m, 0.0);
  EXPECT_NEAR(still.sigma_rad, std::sqrt(10.0) * 0.004, 1e-12);
  EXPECT_NEAR(still.sigma_m, std::sqrt(10 * 0.003 * 0.003 + 10 * 0.004 * 0.004 * 1.0), 1e-12);
  std::vector<Eigen::Isometry3d> drive;
  for (int i = 0; i <= 20; ++i) drive.push_back(headingShift(0.0, Eigen::Vector3d(0.1 * i, 0, 0)));
  const OdometryDrift moved = accumulatedDrift(drive, centre, config, 0.003, 0.004);
  EXPECT_NEAR(moved.path_m, 2.0, 1e-9);
  const double rad = std::sqrt(20 * 0.004 * 0.004 + std::pow(config.drift_rad_per_m * 2.0, 2));
  EXPECT_NEAR(moved.sigma_rad, rad, 1e-12);
  const double lever = std::sqrt(4.0 + 1.0);  // the path's far end to the centre
  EXPECT_NEAR(moved.sigma_m,
              std::sqrt(20 * 0.003 * 0.003 + std::pow(config.drift_fraction * 2.0, 2) +
                        rad * rad * lever * lever),
              1e-9);
  // A correction of 17 cm and 7 degrees: beyond a camera standing still, within the drive.
  const Eigen::Isometry3d correction = headingShift(7.0, Eigen::Vector3d(0.17, 0.0, 0.0));
  std::vector<LabelledPoint> map, detections;
  const double xy[][2] = {{0.0, 0.0}, {0.12, 0.05}, {0.05, 0.16}, {-0.08, 0.1}, {0.1, -0.1}};
  const char* classes[] = {"mug", "can", "box", "bowl", "can"};
  for (int i = 0; i < 5; ++i) {
    map.push_back({classes[i], Eigen::Vector3d(xy[i][0], xy[i][1], 1.0)});
    detections.push_back({classes[i], correction.inverse() * map.back().position});
  }
  const Relocalisation refused =
      relocalise(detections, map, -Eigen::Vector3d::UnitZ(), config, still);
  EXPECT_EQ(refused.decision, RelocalisationDecision::kBeyondDrift);
  EXPECT_FALSE(refused.applied);
  EXPECT_EQ(refused.inliers_after, 5);  // the correction it refused would explain them all
  const Relocalisation allowed =
      relocalise(detections, map, -Eigen::Vector3d::UnitZ(), config, moved);
  EXPECT_TRUE(allowed.applied) << toString(allowed.decision);
}

// Issue 32's first case: a near-symmetric table of five objects (two cans, a mug, two flat boxes
// the detector confuses at times), the camera moving about half a metre around it and never
// leaving; detections from a colour-only estimator, harsher than the issue's: 70 % 2-4 cm off
// along the ray, 30 % coarse failures 10-27 cm off, the flat boxes swapped 20 % of the time. The
// odometry is good (a few millimetres). No relocalisation is applied and the camera stays within
// the odometry's error.
TEST(Relocalisation, ACameraThatNeverLeavesIsNotRelocalised) {
  const ModelSet models = ModelSet::builtinPrimitives();
  test::TableScene scene(models);
  scene.place("005_tomato_soup_can", -0.1, 0.06);
  scene.place("005_tomato_soup_can", 0.1, 0.06);
  scene.place("025_mug", 0.0, -0.01);
  scene.place("008_pudding_box", -0.11, -0.1, 0.1);
  scene.place("009_gelatin_box", 0.11, -0.1, -0.1);
  struct Run {
    int searched = 0, applied = 0;
    double worst_camera = 0.0, worst_odometry = 0.0;
  };
  auto run = [&](const EstimatorConfig& config) {
    std::mt19937 rng(32);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 1.0);
    SceneEstimator estimator(models, config, test::sharedRenderer());
    Eigen::Isometry3d odometry_error = Eigen::Isometry3d::Identity();
    Run out;
    for (int t = 0; t < 40; ++t) {
      // An arc of +-30 degrees about the table (about half a metre of path each way).
      const double a = 0.5 * std::sin(t * 0.16);
      const Eigen::Vector3d eye(0.66 * std::sin(a), -0.66 * std::cos(a), 0.46);
      scene.setCamera(lookAt(eye, Eigen::Vector3d(0.0, 0.0, 0.06)));
      scene.renderObserved(100 + t);
      odometry_error =
          headingShift(0.05 * gauss(rng), 0.0015 * Eigen::Vector3d(gauss(rng), gauss(rng), 0)) *
          odometry_error;
      Keyframe kf = scene.keyframe(t, {0, 1, 2, 3, 4}, odometry_error);
      for (ObjectMeasurement& m : kf.detections) {
        const Eigen::Vector3d ray = m.T_cam_obj.translation().normalized();
        const double along = uni(rng) < 0.3 ? 0.10 + 0.17 * uni(rng) : 0.02 + 0.02 * uni(rng);
        m.T_cam_obj.translation() += (uni(rng) < 0.5 ? along : -along) * ray;
        const bool swap = uni(rng) < 0.2;
        if (swap && m.class_name == "008_pudding_box")
          m.class_name = "009_gelatin_box";
        else if (swap && m.class_name == "009_gelatin_box")
          m.class_name = "008_pudding_box";
      }
      const KeyframeResult r = estimator.addKeyframe(kf);
      out.searched += r.relocalisation.tried;
      out.applied += r.relocalisation.applied;
      const Eigen::Vector3d truth = scene.T_world_cam().translation();
      out.worst_camera = std::max(out.worst_camera, (r.T_map_cam.translation() - truth).norm());
      out.worst_odometry =
          std::max(out.worst_odometry, (kf.T_odom_cam.translation() - truth).norm());
    }
    std::printf(
        "relocalisation searched at %d of 40 keyframes, applied %d; camera error at most "
        "%.1f mm, odometry's %.1f mm\n",
        out.searched, out.applied, 1000 * out.worst_camera, 1000 * out.worst_odometry);
    return out;
  };
  const Run defaults = run(EstimatorConfig());
  // The rules that refuse a wrong correction outright are tested on their own above
  // (AnAmbiguousLayoutIsRefused, DriftGrowsWithThePathAndTheLeverArm).
  EXPECT_GT(defaults.searched, 0) << "never searched: the case is not exercised";
  EXPECT_EQ(defaults.applied, 0);
  EXPECT_LE(defaults.worst_camera, defaults.worst_odometry + 0.01);
}

}  // namespace
}  // namespace geofusion
