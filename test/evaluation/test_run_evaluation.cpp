// The benchmark's evaluator on hand-made cases with known answers: projected boxes against a hand
// computation, perfect estimates, a shifted estimate, a missed object, a false object, contacts
// of the wrong type, objects sunk into or floating above the table, a map frame that is not the
// ground truth's; and the results file round trip it reads.
#include "geofusion/evaluation/run_evaluation.h"
#include "geofusion/evaluation/trajectory_metrics.h"

#include "geofusion/estimation/map_stability.h"
#include "geofusion/estimation/run_results.h"
#include "geofusion/model/object_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>

namespace geofusion {
namespace {

Eigen::Isometry3d translation(double x, double y, double z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

// A camera held nearly still (the real YCB-Video frames move 4 mm) leaves the rotation of the
// alignment to the noise: only the offset is taken, so the map is not turned about the camera.
TEST(TrajectoryAlignment, AStillCameraIsAlignedByItsOffsetAlone) {
  std::vector<Eigen::Vector3d> truth, est;
  for (int k = 0; k < 10; ++k) {
    truth.emplace_back(0.001 * k, 0.0005 * (k % 3), 0.4);
    // Estimated 2 cm off, with 1 mm of noise that a rotation could "explain".
    est.push_back(truth.back() + Eigen::Vector3d(0.02, 0.0, 0.0) +
                  0.001 * Eigen::Vector3d(std::sin(k), std::cos(3 * k), std::sin(7 * k)));
  }
  double rmse = 0.0;
  const Eigen::Isometry3d T = alignTrajectories(est, truth, &rmse);
  EXPECT_LT((T.linear() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_NEAR(T.translation().x(), -0.02, 0.001);
  EXPECT_LT(rmse, 0.002);
  // A trajectory spanning a plane is aligned in full: a turned copy is turned back.
  std::vector<Eigen::Vector3d> arc, turned;
  const Eigen::AngleAxisd turn(0.3, Eigen::Vector3d::UnitZ());
  for (int k = 0; k < 20; ++k) {
    arc.emplace_back(std::cos(0.1 * k), std::sin(0.1 * k), 1.0);
    turned.push_back(turn * arc.back());
  }
  const Eigen::Isometry3d U = alignTrajectories(turned, arc, &rmse);
  EXPECT_NEAR(Eigen::AngleAxisd(U.linear()).angle(), 0.3, 1e-9);
  EXPECT_LT(rmse, 1e-9);
}

TEST(ProjectedBox, MatchesAHandComputationAndIsClippedToTheImage) {
  PinholeIntrinsics K;
  K.width = 640;
  K.height = 480;
  K.fx = K.fy = 500.0;
  K.cx = 320.0;
  K.cy = 240.0;
  const std::vector<Eigen::Vector3f> points = {
      {-0.1f, -0.05f, 0.0f}, {0.1f, -0.05f, 0.0f}, {0.1f, 0.05f, 0.0f}, {-0.1f, 0.05f, 0.0f}};
  // 1 m in front: x 320 -+ 500 * 0.1, y 240 -+ 500 * 0.05.
  Box2d b = projectedBox(points, translation(0, 0, 1), K);
  EXPECT_NEAR(b.x0, 270.0, 1e-5);  // float model points
  EXPECT_NEAR(b.x1, 370.0, 1e-5);  // float model points
  EXPECT_NEAR(b.y0, 215.0, 1e-5);  // float model points
  EXPECT_NEAR(b.y1, 265.0, 1e-5);  // float model points
  // 0.6 m to the right: x from 570 to 670, clipped at the image's edge.
  b = projectedBox(points, translation(0.6, 0, 1), K);
  EXPECT_NEAR(b.x0, 570.0, 1e-5);  // float model points
  EXPECT_NEAR(b.x1, 640.0, 1e-5);  // float model points
  // IoU by hand: two 100 x 50 boxes overlapping by half their width: 2500 / (5000 + 5000 - 2500).
  Box2d a, c;
  a.x0 = 0, a.x1 = 100, a.y0 = 0, a.y1 = 50;
  c.x0 = 50, c.x1 = 150, c.y0 = 0, c.y1 = 50;
  EXPECT_NEAR(boxIou(a, c), 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(boxIou(a, a), 1.0, 1e-12);
  c.x0 = 200, c.x1 = 300;
  EXPECT_EQ(boxIou(a, c), 0.0);
  // Outside the image, or behind the camera: no box.
  EXPECT_TRUE(projectedBox(points, translation(2.0, 0, 1), K).empty());
  EXPECT_TRUE(projectedBox(points, translation(0, 0, -1), K).empty());
}

// A scene of two primitive objects on the table, seen by three keyframes; the models' evaluation
// points are their bounding-box corners, so that ADD-S of a shift is known exactly.
class RunEvaluationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const ModelSet primitives = ModelSet::builtinPrimitives();
    for (const char* name : {"003_cracker_box", "061_foam_brick"}) {
      auto m = std::make_shared<ObjectModel>(*primitives.find(name));
      const Eigen::Vector3f lo = m->extents * -0.5f, hi = m->extents * 0.5f;
      m->points.clear();
      for (int c = 0; c < 8; ++c)
        m->points.emplace_back(c & 1 ? hi.x() : lo.x(), c & 2 ? hi.y() : lo.y(),
                               c & 4 ? hi.z() : lo.z());
      models.push_back(m);
    }
    gt.scene_name = "hand_made";
    gt.intrinsics.width = 640;
    gt.intrinsics.height = 480;
    gt.intrinsics.fx = gt.intrinsics.fy = 525.0;
    gt.intrinsics.cx = 320.0;
    gt.intrinsics.cy = 240.0;
    const double table = gt.scene.table.height_m;
    for (int i = 0; i < 2; ++i) {
      SceneObject o;
      o.model = models[static_cast<std::size_t>(i)];
      // Resting on the table: the lowest hull vertex at the table's height.
      double lowest = std::numeric_limits<double>::infinity();
      for (const auto& v : o.model->collision_hull.vertices)
        lowest = std::min(lowest, static_cast<double>(v.z()));
      o.T_world_obj = translation(i == 0 ? -0.12 : 0.12, 0.0, table - lowest);
      gt.scene.objects.push_back(o);
      FeatureContact c;
      c.object_a = -1;
      c.object_b = i;
      c.type = ContactType::kPlanePlane;
      c.kind = ContactKind::kSupport;
      gt.scene.contacts.push_back(c);
    }
    // Cameras 0.9 m above the table looking down, along a line.
    for (int k = 0; k < 3; ++k) {
      GroundTruthFrame f;
      f.index = 6 * k;
      f.stamp_s = 100.0 + 0.2 * k;
      f.keyframe = true;
      f.T_map_optical = translation(-0.05 + 0.05 * k, 0.0, table + 0.9);
      f.T_map_optical.linear() = Eigen::Vector3d(1, -1, -1).asDiagonal();  // z down, y flipped
      f.visible_fraction = {0.8, k == 2 ? 0.05 : 0.7};  // the brick nearly hidden in the last
      f.visible_pixels = {4000, k == 2 ? 100 : 3000};
      gt.frames.push_back(f);
    }
    // Perfect results.
    results.method = "GeoFusion";
    results.recording_duration_s = 0.6;
    results.wall_time_s = 0.06;
    for (int k = 0; k < 3; ++k) {
      KeyframeResult r;
      r.keyframe = k;
      r.stamp_s = gt.frames[static_cast<std::size_t>(k)].stamp_s;
      r.T_map_cam = gt.frames[static_cast<std::size_t>(k)].T_map_optical;
      r.timings.total_ms = 10.0 + k;
      for (int i = 0; i < 2; ++i) {
        ObjectEstimate e;
        e.id = 10 + i;
        e.model = models[static_cast<std::size_t>(i)];
        e.T_map_obj = gt.scene.objects[static_cast<std::size_t>(i)].T_world_obj;
        e.existence = 0.9;
        r.objects.push_back(e);
      }
      results.keyframes.push_back(r);
      results.trajectory.push_back(r.T_map_cam);
      results.trajectory_stamps.push_back(r.stamp_s);
    }
    results.final_map = results.keyframes.back();
    results.final_map.contacts = gt.scene.contacts;  // indices 0, 1 into the final objects
  }

  RunEvaluation evaluate() {
    RunEvaluation ev;
    std::string error;
    EXPECT_TRUE(evaluateRun(gt, results, EvaluationConfig(), &ev, &error)) << error;
    return ev;
  }

  std::vector<std::shared_ptr<ObjectModel>> models;
  GroundTruth gt;
  RunResults results;
};

// An object that leaves the online map for a keyframe and comes back: one departure, one return
// (a flip-flop); lost only when it was well seen and the absence is longer than allowed.
TEST_F(RunEvaluationTest, ObjectLifecycleCountsDeparturesReturnsAndLosses) {
  results.keyframes[1].objects.pop_back();  // the brick is out of the map at keyframe 1
  EvaluationConfig strict;
  strict.well_seen_min_keyframes = 2;  // the brick is at least half visible in 2 keyframes
  strict.lost_absence_keyframes = 0;
  RunEvaluation ev;
  std::string error;
  ASSERT_TRUE(evaluateRun(gt, results, strict, &ev, &error)) << error;
  ASSERT_TRUE(ev.has_lifecycle);
  ASSERT_EQ(ev.lifecycle.size(), 2u);
  const ObjectLifecycle& box = ev.lifecycle[0];
  EXPECT_EQ(box.first_mapped, 0);
  EXPECT_EQ(box.departures, 0);
  EXPECT_EQ(box.returns, 0);
  EXPECT_TRUE(box.in_final_map);
  EXPECT_FALSE(box.lost);
  const ObjectLifecycle& brick = ev.lifecycle[1];
  EXPECT_EQ(brick.well_seen_keyframes, 2);
  EXPECT_EQ(brick.first_mapped, 0);
  EXPECT_EQ(brick.departures, 1);
  EXPECT_EQ(brick.returns, 1);
  EXPECT_EQ(brick.longest_absence, 1);
  EXPECT_TRUE(brick.in_final_map);
  EXPECT_TRUE(brick.lost);  // absent for 1 keyframe > 0 allowed
  // With the default thresholds (20 well-seen keyframes) nothing here counts as lost.
  const RunEvaluation relaxed = evaluate();
  for (const ObjectLifecycle& l : relaxed.lifecycle) EXPECT_FALSE(l.lost);
  // A map that moved away is not "in the map": an estimate 10 cm off is another object.
  results.keyframes[2].objects[0].T_map_obj.translation().x() += 0.1;
  ASSERT_TRUE(evaluateRun(gt, results, strict, &ev, &error));
  EXPECT_EQ(ev.lifecycle[0].departures, 1);
  EXPECT_EQ(ev.lifecycle[0].returns, 0);
  // FbF has no persistent map: no lifecycle.
  results.method = "FbF";
  ASSERT_TRUE(evaluateRun(gt, results, strict, &ev, &error));
  EXPECT_FALSE(ev.has_lifecycle);
}

// A changed scene: the brick is taken away at camera frame 6 (keyframe 1). Kept in the map at
// keyframe 1 and gone at keyframe 2, it took one keyframe to let go; kept to the end, it is a
// ghost. Either way the final map is scored against the box alone, and the brick's contact with
// the table is no longer true.
TEST_F(RunEvaluationTest, AnObjectTakenAwayIsScoredByHowLongTheMapKeptIt) {
  gt.scene.objects[1].present_until_frame = 6;
  results.keyframes[2].objects.pop_back();
  results.final_map = results.keyframes.back();
  results.final_map.contacts = {gt.scene.contacts[0]};
  RunEvaluation ev = evaluate();
  ASSERT_TRUE(ev.has_lifecycle);
  const ObjectLifecycle& brick = ev.lifecycle[1];
  EXPECT_EQ(brick.removed_keyframe, 1);
  EXPECT_EQ(brick.last_mapped, 1);
  EXPECT_EQ(brick.removal_latency, 1);
  EXPECT_FALSE(brick.ghost);
  EXPECT_FALSE(brick.lost);
  EXPECT_EQ(ev.true_objects, 1);
  EXPECT_EQ(ev.map_matched, 1);
  EXPECT_EQ(ev.true_contacts, 1);
  EXPECT_EQ(ev.correct_contacts, 1);
  // No ground-truth box for the brick after it left.
  for (const GroundTruthBox& g : ev.ground_truth) EXPECT_FALSE(g.object == 1 && g.image == 2);
  // Its old place hidden at keyframe 1 (the ground truth says how much of it the camera sees):
  // the latency counts from keyframe 2, where it is seen empty and the map has let go.
  for (GroundTruthFrame& f : gt.frames) {
    if (!f.keyframe) continue;
    f.place_visible_fraction.assign(gt.scene.objects.size(), -1.0);
    if (f.index >= 6) f.place_visible_fraction[1] = f.index < 11 ? 0.2 : 0.9;
  }
  const RunEvaluation hidden = evaluate();
  EXPECT_EQ(hidden.lifecycle[1].removed_keyframe, 2);
  EXPECT_EQ(hidden.lifecycle[1].removal_latency, 0);
  for (GroundTruthFrame& f : gt.frames) f.place_visible_fraction.clear();
  // Gone at once: latency 0.
  results.keyframes[1].objects.pop_back();
  EXPECT_EQ(evaluate().lifecycle[1].removal_latency, 0);
  // Kept to the end: a ghost, and a false object of the final map.
  models.clear();
  gt = GroundTruth();
  results = RunResults();
  SetUp();
  gt.scene.objects[1].present_until_frame = 6;
  ev = evaluate();
  EXPECT_TRUE(ev.lifecycle[1].ghost);
  EXPECT_EQ(ev.lifecycle[1].removal_latency, -1);
  EXPECT_EQ(ev.map_objects, 2);
  EXPECT_EQ(ev.map_matched, 1);
}

TEST_F(RunEvaluationTest, PerfectEstimatesMatchEverythingWithZeroError) {
  const RunEvaluation ev = evaluate();
  ASSERT_EQ(ev.images.size(), 3u);
  EXPECT_EQ(ev.unmatched_keyframes, 0);
  ASSERT_EQ(ev.ground_truth.size(), 6u);
  ASSERT_EQ(ev.detections.size(), 6u);
  int crowds = 0;
  for (const GroundTruthBox& g : ev.ground_truth) crowds += g.crowd;
  EXPECT_EQ(crowds, 1);  // the brick at 5 % visible
  for (std::size_t d = 0; d < ev.detections.size(); ++d) {
    const DetectionBox& det = ev.detections[d];
    const GroundTruthBox& g = ev.ground_truth[d];  // same order: image, then object
    EXPECT_EQ(det.image, g.image);
    EXPECT_NEAR(det.box.x0, g.box.x0, 1e-6);
    EXPECT_NEAR(det.box.y1, g.box.y1, 1e-6);
    EXPECT_DOUBLE_EQ(det.score, 0.9);
    if (g.crowd) {
      EXPECT_TRUE(det.adds_m.empty());  // no ADD-S against ignored ground truth
    } else {
      ASSERT_EQ(det.adds_m.size(), 1u);  // one object of its class in the image
      EXPECT_EQ(det.adds_m[0].first, g.id);
      EXPECT_NEAR(det.adds_m[0].second, 0.0, 1e-6);
    }
  }
  EXPECT_EQ(ev.map_objects, 2);
  EXPECT_EQ(ev.map_matched, 2);
  EXPECT_LT(ev.alignment_rmse_m, 1e-6);
  ASSERT_TRUE(ev.has_contacts);
  EXPECT_EQ(ev.true_contacts, 2);
  EXPECT_EQ(ev.estimated_contacts, 2);
  EXPECT_EQ(ev.correct_contacts, 2);
  // Both objects touch the table without sinking in, and nothing floats.
  ASSERT_EQ(ev.penetration_m.size(), 2u);
  for (double p : ev.penetration_m) EXPECT_NEAR(p, 0.0, 1e-6);
  ASSERT_EQ(ev.gap_m.size(), 2u);
  for (double g : ev.gap_m) EXPECT_NEAR(g, 0.0, 1e-6);
  EXPECT_EQ(ev.timings.size(), 3u);
}

TEST_F(RunEvaluationTest, AShiftedEstimateHasTheShiftAsItsAddS) {
  // The cracker box 1 cm off along its x axis in every keyframe: each corner's nearest estimated
  // corner is its own, 1 cm away (the box is far bigger than 1 cm in every direction).
  for (KeyframeResult& k : results.keyframes) k.objects[0].T_map_obj.translation().x() += 0.01;
  const RunEvaluation ev = evaluate();
  for (const DetectionBox& d : ev.detections) {
    if (d.object_id != 10) continue;
    ASSERT_EQ(d.adds_m.size(), 1u);
    EXPECT_NEAR(d.adds_m[0].second, 0.01, 1e-6);
  }
}

TEST_F(RunEvaluationTest, AMissedObjectHasNoDetectionAndAFalseObjectMatchesNothing) {
  results.keyframes[1].objects.pop_back();  // the brick missed in keyframe 1
  ObjectEstimate ghost = results.final_map.objects[0];
  ghost.id = 99;
  ghost.T_map_obj.translation().y() += 0.3;  // a cracker box where there is none
  results.final_map.objects.push_back(ghost);
  const RunEvaluation ev = evaluate();
  EXPECT_EQ(ev.ground_truth.size(), 6u);
  EXPECT_EQ(ev.detections.size(), 5u);
  EXPECT_EQ(ev.map_objects, 3);
  EXPECT_EQ(ev.map_matched, 2);
  ASSERT_EQ(ev.graph_estimated_objects.size(), 3u);
  EXPECT_EQ(ev.graph_estimated_objects[2].match, -1);
}

TEST_F(RunEvaluationTest, ContactsOfTheWrongTypeOrObjectAreWrong) {
  results.final_map.contacts[0].type = ContactType::kPlaneCurve;
  FeatureContact between;  // the two objects do not touch
  between.object_a = 0;
  between.object_b = 1;
  between.kind = ContactKind::kSupport;
  results.final_map.contacts.push_back(between);
  const RunEvaluation ev = evaluate();
  EXPECT_EQ(ev.estimated_contacts, 3);
  EXPECT_EQ(ev.correct_contacts, 1);
  EXPECT_EQ(ev.true_contacts, 2);
  // Per object pair whatever the type: the box on the table is right, the pair of objects wrong.
  EXPECT_EQ(ev.estimated_contact_pairs, 3);
  EXPECT_EQ(ev.correct_contact_pairs, 2);
  EXPECT_EQ(ev.true_contact_pairs, 2);
  // Per kind (pair and kind, whatever the feature types): both table supports are right.
  const ContactCounts& support = ev.contacts_by_kind[static_cast<int>(ContactKind::kSupport)];
  EXPECT_EQ(support.estimated, 3);
  EXPECT_EQ(support.correct, 2);
  EXPECT_EQ(support.truth, 2);
  EXPECT_EQ(ev.contacts_by_kind[static_cast<int>(ContactKind::kSide)].estimated, 0);
  int correct = 0;
  for (const GraphContact& c : ev.graph_estimated_contacts) correct += c.correct;
  EXPECT_EQ(correct, 2);
  // A method without contact inference has no contact figures at all.
  results.method = "R-Front";
  EXPECT_FALSE(evaluate().has_contacts);
}

TEST_F(RunEvaluationTest, MaskBoxesAreTheBoxesOfTheVisiblePixels) {
  for (GroundTruthFrame& f : gt.frames) f.visible_boxes = {PixelBox{10, 20, 30, 40}, PixelBox{}};
  RunEvaluation ev = evaluate();
  ASSERT_EQ(ev.ground_truth.size(), 6u);
  for (const GroundTruthBox& g : ev.ground_truth) {
    if (g.object == 1) {
      EXPECT_TRUE(g.mask_box.empty());  // no visible pixel recorded
      continue;
    }
    EXPECT_DOUBLE_EQ(g.mask_box.x0, 10.0);
    EXPECT_DOUBLE_EQ(g.mask_box.y0, 20.0);
    EXPECT_DOUBLE_EQ(g.mask_box.x1, 40.0);
    EXPECT_DOUBLE_EQ(g.mask_box.y1, 60.0);
    EXPECT_FALSE(g.box.empty());  // the projected-model box is there beside it
  }
  // Ground truth without recorded masks (older files): no mask boxes.
  for (GroundTruthFrame& f : gt.frames) f.visible_boxes.clear();
  ev = evaluate();
  for (const GroundTruthBox& g : ev.ground_truth) EXPECT_TRUE(g.mask_box.empty());
}

// A phantom reported in every keyframe and a brick reported as a cracker box in every keyframe:
// each survives when the final map keeps an unmatched object that it explains.
TEST_F(RunEvaluationTest, PersistentPhantomsAndSwapsInTheFinalMapAreCounted) {
  PhantomObject phantom;
  phantom.host = 0;
  phantom.class_name = models[1]->name;  // a brick 6 cm beside the cracker box
  phantom.T_world_obj = gt.scene.objects[0].T_world_obj * Eigen::Translation3d(0.0, 0.06, 0.0);
  gt.phantoms.push_back(phantom);
  for (GroundTruthFrame& f : gt.frames) {
    f.detection_truth = {0, 1, -2};
    f.swapped = {1};
  }
  EvaluationConfig config;
  config.persistent_min_keyframes = 3;
  RunEvaluation ev;
  std::string error;
  ASSERT_TRUE(evaluateRun(gt, results, config, &ev, &error)) << error;
  EXPECT_EQ(ev.persistent_phantoms, 1);
  EXPECT_EQ(ev.surviving_phantoms, 0);
  EXPECT_EQ(ev.persistent_swaps, 1);
  EXPECT_EQ(ev.surviving_swaps, 0);
  ObjectEstimate ghost = results.final_map.objects[1];  // the phantom, as a brick
  ghost.id = 98;
  ghost.T_map_obj = phantom.T_world_obj;
  ObjectEstimate swapped = results.final_map.objects[0];  // a cracker box where the brick is
  swapped.id = 99;
  swapped.T_map_obj.translation() = gt.scene.objects[1].T_world_obj.translation();
  results.final_map.objects.push_back(ghost);
  results.final_map.objects.push_back(swapped);
  ASSERT_TRUE(evaluateRun(gt, results, config, &ev, &error)) << error;
  EXPECT_EQ(ev.map_matched, 2);
  EXPECT_EQ(ev.surviving_phantoms, 1);
  EXPECT_EQ(ev.surviving_swaps, 1);
  // Reported in fewer keyframes than the threshold: not persistent, not counted.
  config.persistent_min_keyframes = 4;
  ASSERT_TRUE(evaluateRun(gt, results, config, &ev, &error)) << error;
  EXPECT_EQ(ev.persistent_phantoms, 0);
  EXPECT_EQ(ev.surviving_phantoms, 0);
  EXPECT_EQ(ev.persistent_swaps, 0);
}

// The odometry's ATE comes from the recorded odom -> base chain: zero when it is the truth, the
// residual of its own alignment when it bends; the method's own ATE is separate.
TEST_F(RunEvaluationTest, TheOdometrysTrajectoryErrorIsMeasuredBesideTheMethods) {
  EXPECT_LT(evaluate().odometry_ate_rmse_m, 1e-9);
  for (std::size_t k = 0; k < gt.frames.size(); ++k) {
    const double bend = 0.01 * static_cast<double>(k * k);  // 0, 1, 4 cm sideways
    gt.frames[k].T_odom_base = translation(0.0, bend, 0.0) * gt.frames[k].T_map_base;
  }
  const RunEvaluation ev = evaluate();
  EXPECT_LT(ev.alignment_rmse_m, 1e-6);  // the method's cameras are the truth
  EXPECT_GT(ev.odometry_ate_rmse_m, 0.002);
  EXPECT_LT(ev.odometry_ate_rmse_m, 0.04);
}

TEST_F(RunEvaluationTest, SunkAndFloatingObjectsGiveTheirDepthAndGap) {
  results.final_map.objects[0].T_map_obj.translation().z() -= 0.005;  // 5 mm into the table
  results.final_map.objects[1].T_map_obj.translation().z() += 0.003;  // 3 mm above it
  // A false box 0.74 m below, on the floor: under the table, not into it (issue 21: B-SLAM's
  // stray estimates read as interpenetrations of up to 1.77 m).
  ObjectEstimate stray = results.final_map.objects[0];
  stray.id = 77;
  stray.T_map_obj.translation().z() -= 0.74;
  results.final_map.objects.push_back(stray);
  const RunEvaluation ev = evaluate();
  ASSERT_EQ(ev.penetration_m.size(), 1u);  // the floating brick touches nothing
  EXPECT_NEAR(ev.penetration_m[0], 0.005, 1e-6);
  results.final_map.objects.pop_back();
  ASSERT_EQ(ev.gap_m.size(), 2u);
  EXPECT_NEAR(ev.gap_m[0], 0.0, 1e-6);
  EXPECT_NEAR(ev.gap_m[1], 0.003, 1e-6);
  // The method's own support plane is the table when it has one: 5 mm lower, nothing sinks.
  results.support_plane.valid = true;
  results.support_plane.normal = Eigen::Vector3d::UnitZ();
  results.support_plane.height = gt.scene.table.height_m - 0.005;
  const RunEvaluation own = evaluate();
  ASSERT_EQ(own.gap_m.size(), 2u);
  EXPECT_NEAR(own.gap_m[0], 0.0, 1e-6);
  EXPECT_NEAR(own.gap_m[1], 0.008, 1e-6);
}

TEST_F(RunEvaluationTest, AMapFrameOtherThanTheTruthsIsAlignedByTheTrajectory) {
  // The whole estimate in a frame turned 30 degrees and moved: cameras, objects, trajectory.
  Eigen::Isometry3d T_est_true = translation(0.4, -0.2, 0.1);
  T_est_true.linear() = Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  auto move = [&](KeyframeResult* k) {
    k->T_map_cam = T_est_true * k->T_map_cam;
    for (ObjectEstimate& o : k->objects) o.T_map_obj = T_est_true * o.T_map_obj;
  };
  for (KeyframeResult& k : results.keyframes) move(&k);
  move(&results.final_map);
  for (Eigen::Isometry3d& T : results.trajectory) T = T_est_true * T;
  const RunEvaluation ev = evaluate();
  EXPECT_LT(ev.alignment_rmse_m, 1e-6);
  EXPECT_EQ(ev.map_matched, 2);
  EXPECT_EQ(ev.correct_contacts, 2);
  ASSERT_EQ(ev.gap_m.size(), 2u);
  for (double g : ev.gap_m) EXPECT_NEAR(g, 0.0, 1e-6);
  // Per keyframe, camera-frame poses do not depend on the map frame: still exact.
  for (const DetectionBox& d : ev.detections)
    for (const auto& a : d.adds_m) EXPECT_NEAR(a.second, 0.0, 1e-6);
}

TEST_F(RunEvaluationTest, KeyframesNotInTheGroundTruthAreCountedAndSkipped) {
  results.keyframes[2].stamp_s += 0.1;  // between ground-truth keyframes
  const RunEvaluation ev = evaluate();
  EXPECT_EQ(ev.images.size(), 2u);
  EXPECT_EQ(ev.unmatched_keyframes, 1);
  for (KeyframeResult& k : results.keyframes) k.stamp_s += 50.0;
  RunEvaluation none;
  std::string error;
  EXPECT_FALSE(evaluateRun(gt, results, EvaluationConfig(), &none, &error));
  EXPECT_FALSE(error.empty());
}

TEST_F(RunEvaluationTest, ResultsAndEvaluationFilesRoundTrip) {
  ModelSet set = ModelSet::builtinPrimitives();
  // The results file refers to classes by name: read back with the primitive models.
  const std::string path = ::testing::TempDir() + "/geofusion_test_results.yaml";
  results.support_plane.valid = true;
  results.support_plane.height = 0.75;
  results.peak_rss_mb = 123.0;
  results.keyframes[1].stage_one.status = SolveStatus::kConverged;
  results.keyframes[2].stage_one.status = SolveStatus::kFailed;
  results.final_map.stage_two.status = SolveStatus::kCostIncreased;
  // A leaning contact whose normal runs down from a to b: a leans on b. Without the normal in the
  // file the evaluator's support graph had b leaning on a.
  FeatureContact leaning;
  leaning.object_a = 0;
  leaning.object_b = 1;
  leaning.type = ContactType::kPlaneEdge;
  leaning.kind = ContactKind::kLeaning;
  leaning.normal = Eigen::Vector3d(0.6, 0.0, -0.8);
  results.final_map.contacts.push_back(leaning);
  EXPECT_EQ(failedStages(results), 2);
  std::string error;
  ASSERT_TRUE(writeRunResults(path, results, &error)) << error;
  RunResults back;
  ASSERT_TRUE(readRunResults(path, set, &back, &error)) << error;
  EXPECT_EQ(back.method, "GeoFusion");
  ASSERT_EQ(back.keyframes.size(), 3u);
  ASSERT_EQ(back.keyframes[1].objects.size(), 2u);
  EXPECT_EQ(back.keyframes[1].objects[1].model->name, "061_foam_brick");
  EXPECT_TRUE(back.keyframes[1].objects[1].T_map_obj.isApprox(
      results.keyframes[1].objects[1].T_map_obj, 1e-9));
  EXPECT_DOUBLE_EQ(back.keyframes[2].timings.total_ms, 12.0);
  EXPECT_EQ(back.keyframes[0].stage_one.status, SolveStatus::kNotRun);
  EXPECT_EQ(back.keyframes[1].stage_one.status, SolveStatus::kConverged);
  EXPECT_EQ(back.keyframes[2].stage_one.status, SolveStatus::kFailed);
  EXPECT_EQ(back.final_map.stage_two.status, SolveStatus::kCostIncreased);
  EXPECT_EQ(failedStages(back), 2);
  ASSERT_EQ(back.final_map.contacts.size(), 3u);
  EXPECT_TRUE(back.final_map.contacts[2].normal.isApprox(Eigen::Vector3d(0.6, 0.0, -0.8), 1e-9));
  const Eigen::Vector3d down(0, 0, -1);
  const SupportGraph written =
      mapSupportGraph(results.final_map.objects, results.final_map.contacts, down, nullptr);
  const SupportGraph read =
      mapSupportGraph(back.final_map.objects, back.final_map.contacts, down, nullptr);
  EXPECT_EQ(written.find(10)->leans_on, std::vector<int>{11});  // ids of objects 0 and 1
  EXPECT_EQ(read.find(10)->leans_on, std::vector<int>{11});
  EXPECT_EQ(read.removal_order, written.removal_order);
  EXPECT_EQ(back.final_map.contacts[1].object_a, -1);
  EXPECT_EQ(back.final_map.contacts[1].object_b, 1);
  EXPECT_TRUE(back.support_plane.valid);
  EXPECT_DOUBLE_EQ(back.support_plane.height, 0.75);
  EXPECT_DOUBLE_EQ(back.peak_rss_mb, 123.0);
  ASSERT_EQ(back.trajectory.size(), 3u);
  EXPECT_NEAR(back.trajectory_stamps[2], 100.4, 1e-9);

  // A broken file fails with a message naming it.
  std::ofstream(path) << "format: geofusion_results_v1\nmethod: [\n";
  EXPECT_FALSE(readRunResults(path, set, &back, &error));
  EXPECT_NE(error.find(path), std::string::npos);

  const RunEvaluation ev = evaluate();
  const std::string json = ::testing::TempDir() + "/geofusion_test_evaluation.json";
  ASSERT_TRUE(writeEvaluationJson(json, ev, &error)) << error;
  std::ifstream in(json);
  std::stringstream text;
  text << in.rdbuf();
  for (const char* key : {"\"format\":\"geofusion_evaluation_v1\"", "\"annotations\"",
                          "\"iscrowd\":1", "\"adds_m\"", "\"contact_graph\"", "\"timings_ms\""})
    EXPECT_NE(text.str().find(key), std::string::npos) << key;
}

// A ground truth without contacts makes the contact figures meaningless: said, not silent.
TEST_F(RunEvaluationTest, AGroundTruthWithoutContactsIsWarnedAbout) {
  EXPECT_TRUE(evaluate().warnings.empty());
  gt.scene.contacts.clear();
  const RunEvaluation ev = evaluate();
  ASSERT_EQ(ev.warnings.size(), 1u);
  EXPECT_NE(ev.warnings[0].find("no support contact"), std::string::npos);
  EXPECT_NE(summarize(ev).find("warning: the ground truth has no support contact"),
            std::string::npos);
  // A method that infers no contacts has nothing to be wrong about.
  results.method = "B-SLAM";
  EXPECT_TRUE(evaluate().warnings.empty());
}

// A method that solves only every N-th keyframe: the mean carries the solves the median misses,
// and the final solve is reported on its own.
TEST_F(RunEvaluationTest, TheKeyframeTimeMeanCarriesSolvesMadeEveryNthKeyframe) {
  results.method = "B-SLAM";
  results.keyframes[0].timings.total_ms = 0.05;
  results.keyframes[1].timings.total_ms = 0.05;
  results.keyframes[2].timings.total_ms = 30.0;  // the stage I solve
  results.final_map.timings.total_ms = 45.0;
  const RunEvaluation ev = evaluate();
  EXPECT_DOUBLE_EQ(ev.final_solve.total_ms, 45.0);
  const std::string summary = summarize(ev);
  EXPECT_NE(summary.find("10.0 ms mean, 0.1 ms median"), std::string::npos) << summary;
  EXPECT_NE(summary.find("final solve 45.0 ms"), std::string::npos) << summary;
}

}  // namespace
}  // namespace geofusion
