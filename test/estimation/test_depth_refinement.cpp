// Depth refinement of detections on rendered tabletop scenes with the benchmark's depth noise:
// errors along the ray pulled back, a symmetric can's free axis kept, a floating false positive
// and a correction beyond the guard left as they came, and the switch.
#include "geofusion/estimation/depth_refinement.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/model/object_model.h"

#include "table_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

namespace geofusion {
namespace {

using test::TableScene;

constexpr double kDeg = M_PI / 180.0;

// The detection `along` metres too far along its viewing ray, turned by `angle` about `axis`
// (model frame).
Eigen::Isometry3d offRay(const Eigen::Isometry3d& T, double along, const Eigen::Vector3d& axis,
                         double angle) {
  Eigen::Isometry3d out = T;
  out.translation() += along * T.translation().normalized();
  out.linear() = T.linear() * Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  return out;
}

double angleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

class DepthRefinementTest : public ::testing::Test {
 protected:
  DepthRefinementTest() : models(ModelSet::builtinPrimitives()), scene(models) {}

  DepthRefinement refine(int i, const Eigen::Isometry3d& T_cam_obj,
                         const DepthRefinementConfig& config = DepthRefinementConfig()) {
    DepthRefiner refiner(&scene.scorer(), config);
    return refiner.refine(scene.object(i).model, T_cam_obj, scene.depth(), scene.K());
  }

  ModelSet models;
  TableScene scene;
};

// A detection 3 cm too far along the ray and turned 5 degrees, as colour-only estimators err,
// comes back to under 5 mm and 1 degree, and its consistency goes up.
TEST_F(DepthRefinementTest, ADetectionOffAlongTheRayIsPulledBackOntoTheSurface) {
  const int box = scene.place("003_cracker_box", -0.05, 0.05, 0.4);
  const int brick = scene.place("061_foam_brick", 0.15, -0.03, -0.3);
  scene.renderObserved();
  for (int i : {box, brick}) {
    SCOPED_TRACE(scene.object(i).model->name);
    const Eigen::Isometry3d truth = scene.cameraPose(i);
    for (double along : {0.03, -0.03}) {
      const Eigen::Isometry3d detected = offRay(truth, along, Eigen::Vector3d(1, 1, 0), 5 * kDeg);
      const DepthRefinement r = refine(i, detected);
      ASSERT_EQ(r.outcome, RefinementOutcome::kAccepted)
          << toString(r.outcome) << " along " << along << ": corrected by "
          << r.correction_translation_m << " m, " << r.correction_rotation_rad << " rad";
      EXPECT_NEAR(r.ray_offset_m, -along, 0.01);  // the observed surface is in front (behind)
      EXPECT_LT((r.T_cam_obj.translation() - truth.translation()).norm(), 0.005);
      EXPECT_LT(angleBetween(r.T_cam_obj.linear(), truth.linear()), 1 * kDeg);
      EXPECT_GT(r.after.score, r.before.score);
      EXPECT_GT(r.after.r_in, 0.8);
      EXPECT_GT(r.correction_translation_m, 0.025);
    }
  }
}

// Depth cannot see a can turn about its axis: refinement corrects the rest and leaves that
// rotation as detected.
TEST_F(DepthRefinementTest, ASymmetricCanKeepsItsFreeAxis) {
  const int can = scene.place("005_tomato_soup_can", 0.0, 0.0);
  scene.renderObserved();
  const auto& model = *scene.object(can).model;
  ASSERT_EQ(model.symmetry.type, Symmetry::Type::kContinuous);
  const Eigen::Vector3d axis = model.symmetry.axis.normalized();
  const Eigen::Isometry3d truth = scene.cameraPose(can);
  // 2.5 cm too far, turned 40 degrees about the axis and 4 degrees across it.
  Eigen::Isometry3d detected = offRay(truth, 0.025, axis, 40 * kDeg);
  detected.linear() =
      detected.linear() * Eigen::AngleAxisd(4 * kDeg, axis.unitOrthogonal()).toRotationMatrix();
  const DepthRefinement r = refine(can, detected);
  ASSERT_EQ(r.outcome, RefinementOutcome::kAccepted) << toString(r.outcome);
  EXPECT_LT((r.T_cam_obj.translation() - truth.translation()).norm(), 0.005);
  // The axis is where it truly is ...
  const Eigen::Vector3d axis_refined = r.T_cam_obj.linear() * axis,
                        axis_true = truth.linear() * axis;
  EXPECT_LT(std::acos(std::min(1.0, axis_refined.dot(axis_true))), 1.5 * kDeg);
  // ... and the rotation about it is the detected one: no turn about the axis was added.
  const Eigen::AngleAxisd change(detected.linear().transpose() * r.T_cam_obj.linear());
  EXPECT_LT(std::abs(change.angle() * change.axis().dot(axis)), 0.5 * kDeg);
}

// A false positive floating 15 cm above the table: the surface behind it is farther than the
// guard allows, so it is not dragged onto the table and keeps its low score.
TEST_F(DepthRefinementTest, AFloatingFalsePositiveIsNotDraggedOntoTheTable) {
  const int box = scene.place("003_cracker_box", -0.05, 0.05, 0.4);
  const int brick = scene.place("061_foam_brick", 0.15, -0.03, -0.3);
  scene.renderObserved();
  Eigen::Isometry3d floating = scene.object(brick).T_world_obj;
  floating.translation() += Eigen::Vector3d(-0.05, 0.1, 0.12);
  const Eigen::Isometry3d detected = scene.T_world_cam().inverse() * floating;
  const DepthRefinement r = refine(brick, detected);
  EXPECT_NE(r.outcome, RefinementOutcome::kAccepted) << toString(r.outcome);
  EXPECT_TRUE(r.T_cam_obj.isApprox(detected));
  ASSERT_TRUE(r.before.determined);
  EXPECT_LT(r.after.score, 0.2);
  EXPECT_GT(r.ray_offset_m, 0.05);  // the table lies far behind it
  (void)box;
}

// With the guard at 1 cm, a 3 cm correction is refused and the detection stays as it came.
TEST_F(DepthRefinementTest, ACorrectionBeyondTheGuardLeavesTheDetectionAsItCame) {
  const int box = scene.place("003_cracker_box", -0.05, 0.05, 0.4);
  scene.renderObserved();
  const Eigen::Isometry3d detected =
      offRay(scene.cameraPose(box), 0.03, Eigen::Vector3d::UnitZ(), 0.0);
  DepthRefinementConfig guard;
  guard.max_translation_m = 0.01;
  const DepthRefinement r = refine(box, detected, guard);
  EXPECT_EQ(r.outcome, RefinementOutcome::kBeyondGuard);
  EXPECT_TRUE(r.T_cam_obj.isApprox(detected));
  EXPECT_DOUBLE_EQ(r.after.score, r.before.score);
  // Switched off: not attempted, the offset along the ray still measured.
  DepthRefinementConfig off;
  off.enabled = false;
  const DepthRefinement o = refine(box, detected, off);
  EXPECT_EQ(o.outcome, RefinementOutcome::kNotAttempted);
  EXPECT_TRUE(o.T_cam_obj.isApprox(detected));
  EXPECT_NEAR(o.ray_offset_m, -0.03, 0.01);
}

// A stream of keyframes whose detections all sit 3 cm behind the observed surface: with
// refinement off most are rejected and the monitor says so and where they lie; unbiased, or
// refined, there is nothing to say.
TEST_F(DepthRefinementTest, AStreamBiasedAlongTheRayIsReportedUnlessRefined) {
  for (const auto& [name, x, y] :
       {std::tuple{"003_cracker_box", -0.12, 0.06}, std::tuple{"061_foam_brick", 0.15, -0.03},
        std::tuple{"004_sugar_box", 0.02, 0.12}, std::tuple{"005_tomato_soup_can", 0.05, -0.08}})
    scene.place(name, x, y, 0.3);
  scene.renderObserved();
  auto run = [&](double along, bool refine) {
    EstimatorConfig config;
    config.refinement.enabled = refine;
    SceneEstimator estimator(models, config, test::sharedRenderer());
    KeyframeResult last;
    for (int t = 0; t < 12; ++t) {
      Keyframe kf = scene.keyframe(t, {0, 1, 2, 3});
      for (ObjectMeasurement& m : kf.detections)
        m.T_cam_obj = offRay(m.T_cam_obj, along, Eigen::Vector3d::UnitX(), 0.0);
      last = estimator.addKeyframe(kf);
    }
    return last;
  };
  const KeyframeResult biased = run(0.03, false);
  ASSERT_EQ(biased.detections.size(), 4u);
  EXPECT_NE(biased.detection_warning.find("100% of detections rejected as inconsistent with depth "
                                          "over the last 12 keyframes"),
            std::string::npos)
      << biased.detection_warning;
  EXPECT_NE(biased.detection_warning.find(" cm behind the observed surface (median): check depth "
                                          "registration, intrinsics or the detector's depth"),
            std::string::npos)
      << biased.detection_warning;
  for (const DetectionReport& d : biased.detections) {
    EXPECT_EQ(d.refinement, RefinementOutcome::kNotAttempted);
    EXPECT_LT(d.consistency, 0.3);
    EXPECT_NEAR(d.ray_offset_m, -0.03, 0.006);
  }
  EXPECT_TRUE(run(0.0, false).detection_warning.empty());
  const KeyframeResult refined = run(0.03, true);
  EXPECT_TRUE(refined.detection_warning.empty()) << refined.detection_warning;
  for (const DetectionReport& d : refined.detections) {
    EXPECT_EQ(d.refinement, RefinementOutcome::kAccepted);
    EXPECT_GT(d.consistency, 0.5);
    EXPECT_LT((d.T_cam_out.translation() - d.T_cam_in.translation()).norm(), 0.04);
    EXPECT_EQ(d.decision, DetectionDecision::kAssociated);
  }
  EXPECT_EQ(refined.objects.size(), 4u);
}

// Issue 32: a detection 3 cm behind the observed surface renders as almost all hidden (r_occ
// near 1): the inlier ratio of the few points left is no measure of the start pose. The
// refinement is judged by the consistency score then, and accepted.
TEST_F(DepthRefinementTest, ADetectionBehindTheSurfaceIsRefinedAndAccepted) {
  const int flat = scene.place("009_gelatin_box", 0.02, 0.02, 0.5);
  const int pudding = scene.place("008_pudding_box", -0.16, -0.02, -0.2);
  const int can = scene.place("005_tomato_soup_can", 0.17, 0.05);
  scene.renderObserved();
  int hidden_starts = 0;
  for (int i : {flat, pudding, can}) {
    for (double along : {0.03, 0.026, 0.029}) {
      SCOPED_TRACE(scene.object(i).model->name + " " + std::to_string(along));
      const Eigen::Isometry3d truth = scene.cameraPose(i);
      const Eigen::Isometry3d behind = offRay(truth, along, Eigen::Vector3d::UnitX(), 0.0);
      const DepthRefinement r = refine(i, behind);
      ASSERT_EQ(r.outcome, RefinementOutcome::kAccepted)
          << toString(r.outcome) << ": before r_in " << r.before.r_in << " r_occ " << r.before.r_occ
          << ", corrected by " << r.correction_translation_m << " m";
      EXPECT_LT((r.T_cam_obj.translation() - truth.translation()).norm(), 0.005);
      EXPECT_GT(r.after.score, r.before.score);
      if (r.before.r_occ > 0.75) ++hidden_starts;
    }
  }
  EXPECT_GT(hidden_starts, 0) << "no start pose was mostly hidden: the case is not exercised";
}

// The acceptance on its own: r_in decides when enough of the start pose is unhidden, the score
// when almost all of it is hidden (r_in of a handful of points).
TEST(RefinementAcceptance, JudgesAMostlyHiddenStartByTheScore) {
  ConsistencyResult before;
  before.determined = true;
  before.rendered = 1000, before.missing = 0, before.occluded = 996, before.inliers = 4;
  before.r_in = 1.0, before.r_occ = 0.996, before.score = 0.01;
  ConsistencyResult after = before;
  after.occluded = 10, after.inliers = 950, after.outliers = 10, after.uncertain = 30;
  after.r_in = 950.0 / 990.0, after.r_occ = 0.01, after.score = 0.9;
  const DepthRefinementConfig config;
  EXPECT_TRUE(improves(before, after, config));
  DepthRefinementConfig r_in_always;  // the rule before issue 32: r_in 1 can never be beaten
  r_in_always.min_visible_share = 0.0;
  EXPECT_FALSE(improves(before, after, r_in_always));
  EXPECT_FALSE(improves(after, before, config));  // worse by the score too
  // Enough of the start pose unhidden: r_in is defined and decides.
  ConsistencyResult visible = before;
  visible.occluded = 500, visible.inliers = 480, visible.outliers = 20;
  visible.r_in = 0.96, visible.r_occ = 0.5, visible.score = 0.2;
  EXPECT_FALSE(improves(visible, after, config));  // r_in 0.96 -> 0.96: no gain
  after.r_in = 0.98;
  EXPECT_TRUE(improves(visible, after, config));
  after.determined = false;
  EXPECT_FALSE(improves(visible, after, config));
}

// A refined measurement is tight along its ray and keeps the detector's std across it.
TEST(RayAlignedSqrtInformation, IsTightAlongTheRayOnly) {
  const Eigen::Vector3d p(0.3, -0.1, 0.9);
  const Eigen::Matrix3d W = rayAlignedSqrtInformation(p, 0.004, 0.01);
  EXPECT_NEAR((W * p.normalized()).norm(), 1.0 / 0.004, 1e-6);
  const Eigen::Vector3d across = p.normalized().unitOrthogonal();
  EXPECT_NEAR((W * across).norm(), 1.0 / 0.01, 1e-6);
  EXPECT_TRUE(W.isApprox(W.transpose()));
}

}  // namespace
}  // namespace geofusion
