// Stage I and stage II on constructed problems with known answers, and the support plane and
// relations of the estimator.
#include "geofusion/estimation/association.h"
#include "geofusion/estimation/optimization.h"
#include "geofusion/estimation/relations.h"
#include "geofusion/estimation/separation.h"
#include "geofusion/evaluation/metrics.h"
#include "geofusion/model/collision.h"
#include "geofusion/render/renderer.h"

#include "test_geometry.h"

#include <gtest/gtest.h>

#include <random>
#include <tuple>
#include <utility>

namespace geofusion {
namespace {

using namespace test;  // NOLINT: the shared test helpers

const Eigen::Vector3d kGravity(0, 0, -1);

Eigen::Isometry3d perturb(const Eigen::Isometry3d& T, double sigma_t, double sigma_r,
                          std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Isometry3d out = T;
  out.translation() += sigma_t * Eigen::Vector3d(g(rng), g(rng), g(rng));
  const Eigen::Vector3d w = sigma_r * Eigen::Vector3d(g(rng), g(rng), g(rng));
  if (w.norm() > 0)
    out.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix() * out.linear();
  return out;
}

void stageOneCase(double meas_t, double meas_r, double odo_t, double odo_r, double* before_out,
                  double* after_out, double* axis_error);

TEST(StageOne, NoiseFreeInputsStayExact) {
  double before, after, axis;
  stageOneCase(0.0, 0.0, 0.0, 0.0, &before, &after, &axis);
  EXPECT_LT(after, 1e-4);
  EXPECT_LT(axis, 1e-3);
}

TEST(StageOne, KnownAssociationsReducePoseError) {
  double before, after, axis;
  // Per-keyframe odometry noise of a 1-2 cm drift over 200 keyframes, measurement noise of a
  // DenseFusion-like detector. Twelve views: the error drops by about 40 % (the cameras are
  // estimated too; averaging the measurements through the true cameras would give ~ 3.3 mm).
  stageOneCase(0.006, 0.05, 0.001, 0.0015, &before, &after, &axis);
  EXPECT_LT(after, 0.7 * before);
  EXPECT_LT(after, 0.0045);
  // The cans' axes are right although every measurement spun them.
  EXPECT_LT(axis, 0.05);
}

// Stage I run as the estimator runs it (every 10 keyframes, warm-started) over 200 keyframes
// circling five objects, the last one measured in the first `frames_seeing_last_object` only;
// returns the mean object translation error at the end.
double incrementalStageOne(const StageOneConfig& config, int frames_seeing_last_object,
                           std::vector<std::vector<Eigen::Isometry3d>>* history = nullptr,
                           double* last_object_error = nullptr) {
  std::mt19937 rng(11);
  const ObjectModel box = boxModel(0.08, 0.05, 0.15);
  const ObjectModel can = canModel(0.035, 0.1);
  const std::vector<const ObjectModel*> models = {&box, &box, &can, &box, &can};
  std::vector<Eigen::Isometry3d> truth;
  for (int j = 0; j < 5; ++j)
    truth.push_back(
        at(0.1 * j - 0.2, 0.05 * (j % 2), 0.8, rot(20.0 * j, Eigen::Vector3d::UnitZ())));
  const int n = 200;
  std::vector<Eigen::Isometry3d> cams_true, odom;
  Eigen::Isometry3d drift = Eigen::Isometry3d::Identity();
  for (int t = 0; t < n; ++t) {
    const double a = 2.0 * M_PI * t / 100.0;  // twice round
    const Eigen::Isometry3d T =
        lookAt(Eigen::Vector3d(std::cos(a), std::sin(a), 1.3), Eigen::Vector3d(0, 0, 0.8));
    cams_true.push_back(T);
    if (t > 0) drift = drift * perturb(Eigen::Isometry3d::Identity(), 0.001, 0.0015, rng);
    odom.push_back(drift * T);
  }
  std::vector<StageOneMeasurement> meas;
  for (int t = 0; t < n; ++t) {
    for (int j = 0; j < 5; ++j) {
      if (j == 4 && t >= frames_seeing_last_object) continue;
      meas.push_back({t, j, perturb(cams_true[t].inverse() * truth[j], 0.006, 0.05, rng), 1.0});
    }
  }
  std::vector<Eigen::Isometry3d> cams, objects;
  for (int j = 0; j < 5; ++j)
    objects.push_back(odom[0] * meas[static_cast<std::size_t>(j)].T_cam_obj);
  for (int upto = 10; upto <= n; upto += 10) {
    while (static_cast<int>(cams.size()) < upto) {
      const std::size_t t = cams.size();
      cams.push_back(t == 0 ? odom[0] : cams.back() * (odom[t - 1].inverse() * odom[t]));
    }
    std::vector<StageOneMeasurement> seen;
    for (const auto& m : meas)
      if (m.keyframe < upto) seen.push_back(m);
    const std::vector<Eigen::Isometry3d> odom_now(odom.begin(), odom.begin() + upto);
    EXPECT_TRUE(optimizeStageOne(&cams, odom_now, &objects, models, seen, config).solved) << upto;
    if (history) history->push_back(objects);
  }
  if (last_object_error)
    *last_object_error = (objects[4].translation() - truth[4].translation()).norm();
  double e = 0;
  for (int j = 0; j < 5; ++j) e += (objects[j].translation() - truth[j].translation()).norm() / 5;
  return e;
}

// Issue 22: marginalising the keyframes outside the window keeps the full solve's accuracy, and
// an object the window no longer sees keeps its pose.
TEST(StageOne, MarginalisedWindowMatchesTheFullSolve) {
  StageOneConfig full, window;
  full.window_keyframes = 0;
  window.window_keyframes = 30;
  window.marginalise_outside_window = true;
  const double e_full = incrementalStageOne(full, 200);
  const double e_window = incrementalStageOne(window, 200);
  std::printf("object translation error: full %.2f mm, marginalised window %.2f mm\n",
              1000 * e_full, 1000 * e_window);
  EXPECT_LT(e_window, 1.1 * e_full + 0.0002);
  EXPECT_LT(e_window, 0.003);
  // Folding the cameras outside the window is the fixed window at the window's cost: the same
  // answer (the robust loss on the folded measurements aside).
  StageOneConfig fixed = window;
  fixed.marginalise_outside_window = false;
  const double e_fixed = incrementalStageOne(fixed, 200);
  std::printf("fixed window %.2f mm\n", 1000 * e_fixed);
  EXPECT_NEAR(e_window, e_fixed, 0.0002);

  // Object 4 measured in the first 100 keyframes only: once the window (30 keyframes and its
  // anchor) has passed its last measurement, the solves leave it where it was.
  std::vector<std::vector<Eigen::Isometry3d>> history;
  double last_error = 0.0;
  incrementalStageOne(window, 100, &history, &last_error);
  ASSERT_EQ(history.size(), 20u);
  EXPECT_TRUE(history[13][4].isApprox(history[19][4], 1e-12));  // after keyframes 140 and 200
  EXPECT_FALSE(history[13][0].isApprox(history[19][0], 1e-9));  // the others still move
  EXPECT_LT(last_error, 0.005);
}

// Issue 22: measurements from cameras that no longer move, folded into one prior, pull the
// object to the same pose as the measurements themselves (translation exactly, rays included;
// rotation to the chordal mean), whatever symmetric equivalent each measurement reported.
TEST(StageOne, FoldedMeasurementsActLikeTheMeasurements) {
  std::mt19937 rng(5);
  ObjectModel box = boxModel(0.08, 0.05, 0.15);  // discrete symmetry: half turns
  const ObjectModel can = canModel(0.035, 0.1);  // continuous about z
  box.symmetry.type = Symmetry::Type::kDiscrete;
  for (int axis = 0; axis < 3; ++axis)
    box.symmetry.rotations.emplace_back(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::Unit(axis)));
  StageOneConfig config;
  config.measurement_loss.type = "none";
  for (const ObjectModel* model : std::vector<const ObjectModel*>{&box, &can}) {
    const Eigen::Isometry3d truth = at(0.1, -0.05, 0.8, rot(30.0, Eigen::Vector3d(1, 2, 3)));
    std::vector<Eigen::Isometry3d> cams;
    std::vector<StageOneMeasurement> meas;
    FoldedMeasurements folded;
    for (int t = 0; t < 12; ++t) {
      const double a = 0.5 * t;
      cams.push_back(
          lookAt(Eigen::Vector3d(std::cos(a), std::sin(a), 1.3), Eigen::Vector3d(0, 0, 0.8)));
      Eigen::Isometry3d z = perturb(cams.back().inverse() * truth, 0.006, 0.05, rng);
      // The detector reports another symmetric equivalent now and then.
      if (model->symmetry.type == Symmetry::Type::kDiscrete && t % 3 == 0)
        z.linear() = z.linear() * model->symmetry.rotations.front().toRotationMatrix();
      if (model->symmetry.type == Symmetry::Type::kContinuous)
        z.linear() = z.linear() * Eigen::AngleAxisd(0.7 * t, model->symmetry.axis).matrix();
      meas.push_back({t, 0, z, 1.0 + 0.1 * t, t % 2 ? 0.002 : 0.0});
      folded.add(cams.back(), meas.back(), model, truth.linear(), config);
    }
    EXPECT_EQ(folded.count(), 12);
    // The same measurements in stage I with their cameras fixed: a window of one free camera,
    // a last one that measures nothing, all the others outside the window.
    std::vector<Eigen::Isometry3d> objects = {truth}, cams_in = cams;
    cams_in.push_back(cams.back());
    StageOneConfig fixed = config;
    fixed.window_keyframes = 1;
    fixed.max_iterations = 50;
    ASSERT_TRUE(optimizeStageOne(&cams_in, cams_in, &objects, {model}, meas, fixed).solved);
    const Eigen::Isometry3d mean = folded.mean();
    EXPECT_LT((mean.translation() - objects[0].translation()).norm(), 1e-5) << model->name;
    EXPECT_LT(symmetricRotationError(model->symmetry, mean.linear(), objects[0].linear()), 0.002)
        << model->name;
    EXPECT_LT((mean.translation() - truth.translation()).norm(), 0.012) << model->name;
    // Its covariance is the inverse of the summed information.
    EXPECT_GT(folded.covariance()(0, 0), 0.0);
    EXPECT_LT(std::sqrt(folded.covariance()(0, 0)), 0.01 / std::sqrt(12.0));
  }
}

TEST(StageOne, AlignToReferenceTurnsAboutTheContinuousAxis) {
  const ObjectModel can = canModel(0.035, 0.1);
  const Eigen::Matrix3d R_ref = rot(40.0, Eigen::Vector3d(0.3, -1, 0.2));
  const Eigen::Matrix3d R_meas = R_ref * Eigen::AngleAxisd(2.5, can.symmetry.axis).matrix() *
                                 Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitX()).matrix();
  const Eigen::Matrix3d aligned = alignToReference(can.symmetry, R_ref, R_meas);
  EXPECT_NEAR(Eigen::AngleAxisd(R_ref.transpose() * aligned).angle(), 0.02, 1e-6);
  EXPECT_LT((aligned * can.symmetry.axis - R_meas * can.symmetry.axis).norm(), 1e-9);
}

void stageOneCase(double meas_t, double meas_r, double odo_t, double odo_r, double* before_out,
                  double* after_out, double* axis_error) {
  std::mt19937 rng(7);
  const ObjectModel box = boxModel(0.08, 0.05, 0.15);
  const ObjectModel can = canModel(0.035, 0.1);
  std::vector<const ObjectModel*> models = {&box, &box, &can, &box, &can};
  std::vector<Eigen::Isometry3d> truth;
  for (int j = 0; j < 5; ++j)
    truth.push_back(
        at(0.1 * j - 0.2, 0.05 * (j % 2), 0.8, rot(20.0 * j, Eigen::Vector3d::UnitZ())));
  // Cameras on an arc looking at the objects; odometry drifts.
  std::vector<Eigen::Isometry3d> cams_true, odom;
  Eigen::Isometry3d drift = Eigen::Isometry3d::Identity();
  for (int t = 0; t < 12; ++t) {
    const double a = -0.6 + 0.1 * t;
    const Eigen::Vector3d eye(1.0 * std::cos(a), 1.0 * std::sin(a), 1.3);
    const Eigen::Vector3d z = (Eigen::Vector3d(0, 0, 0.8) - eye).normalized();
    const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear().col(0) = x, T.linear().col(1) = z.cross(x), T.linear().col(2) = z;
    T.translation() = eye;
    cams_true.push_back(T);
    if (t > 0) drift = drift * perturb(Eigen::Isometry3d::Identity(), odo_t, odo_r, rng);
    odom.push_back(drift * T);
  }
  odom[0] = cams_true[0];
  std::vector<StageOneMeasurement> meas;
  for (int t = 0; t < 12; ++t) {
    for (int j = 0; j < 5; ++j) {
      Eigen::Isometry3d z = perturb(cams_true[t].inverse() * truth[j], meas_t, meas_r, rng);
      if (models[j] == &can)  // the detector's spin about a can's axis is arbitrary
        z.linear() = z.linear() * rot(360.0 * (t * 37 % 100) / 100.0, Eigen::Vector3d::UnitZ());
      meas.push_back({t, j, z, 1.0});
    }
  }
  // Initial estimate: odometry cameras, objects from their first measurement.
  std::vector<Eigen::Isometry3d> cams = odom, objects;
  for (int j = 0; j < 5; ++j)
    objects.push_back(odom[0] * meas[static_cast<std::size_t>(j)].T_cam_obj);
  auto terror = [&](const std::vector<Eigen::Isometry3d>& o) {
    double e = 0;
    for (int j = 0; j < 5; ++j) e += (o[j].translation() - truth[j].translation()).norm() / 5;
    return e;
  };
  // Plain average of the measurements' positions (what averaging alone would give).
  std::vector<Eigen::Isometry3d> avg(5, Eigen::Isometry3d::Identity());
  for (int j = 0; j < 5; ++j) {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int t = 0; t < 12; ++t)
      p += cams_true[t] * meas[static_cast<std::size_t>(t * 5 + j)].T_cam_obj.translation() / 12.0;
    avg[j].translation() = p;
  }
  std::printf("translation error: first %.2f mm, average %.2f mm\n", 1000 * terror(objects),
              1000 * terror(avg));
  auto error = [&](const std::vector<Eigen::Isometry3d>& o) {
    double e = 0;
    for (int j = 0; j < 5; ++j) e += addsError(models[j]->points, o[j], truth[j]) / 5;
    return e;
  };
  const double before = error(objects);
  const StageOneSummary s = optimizeStageOne(&cams, odom, &objects, models, meas, StageOneConfig());
  ASSERT_TRUE(s.solved) << s.message;
  const double after = error(objects);
  std::printf("translation error after %.2f mm\n", 1000 * terror(objects));
  std::printf("stage I: mean ADD-S %.2f mm -> %.2f mm, last camera %.2f -> %.2f mm\n",
              1000 * before, 1000 * after,
              1000 * (odom.back().translation() - cams_true.back().translation()).norm(),
              1000 * (cams.back().translation() - cams_true.back().translation()).norm());
  EXPECT_TRUE(cams[0].isApprox(odom[0]));  // the first pose is fixed
  *before_out = before;
  *after_out = after;
  *axis_error = symmetricRotationError(can.symmetry, objects[2].linear(), truth[2].linear());
}

// The table as the grounded support: a plane at z = 0.75.
struct Ground {
  std::shared_ptr<ObjectModel> model;
  PosedModel posed;
  Ground() {
    SupportPlane plane;
    plane.valid = true;
    plane.height = 0.75;
    plane.centre = Eigen::Vector3d(0, 0, 0.75);
    plane.size = Eigen::Vector2d(1.2, 0.8);
    Eigen::Isometry3d T;
    model = supportPlaneModel(plane, &T);
    posed = {model.get(), T};
  }
};

TEST(StageTwo, RemovesInterpenetrationAndFloating) {
  const Ground ground;
  const ObjectModel box = boxModel(0.1, 0.1, 0.05);
  // Bottom box 5 mm into the table, top box floating 5 mm above it, both slightly tilted.
  const Eigen::Isometry3d bottom_true = at(0, 0, 0.775), top_true = at(0.01, 0, 0.825);
  std::vector<Eigen::Isometry3d> priors = {at(0, 0, 0.770, rot(1.5, Eigen::Vector3d::UnitX())),
                                           at(0.01, 0, 0.825, rot(-1.5, Eigen::Vector3d::UnitY()))};
  std::vector<const ObjectModel*> models = {&box, &box};
  std::vector<PosedModel> posed = {{&box, priors[0]}, {&box, priors[1]}};
  ContactConfig cc;
  const auto contacts = inferRelations(posed, &ground.posed, kGravity, cc);
  int table_contacts = 0, stacked = 0;
  for (const auto& c : contacts) {
    EXPECT_EQ(c.type, ContactType::kPlanePlane);
    table_contacts += c.object_a == -1 && c.object_b == 0;
    stacked += c.object_a == 0 && c.object_b == 1;
  }
  ASSERT_EQ(table_contacts, 1);
  ASSERT_EQ(stacked, 1);
  std::vector<Eigen::Isometry3d> poses = priors;
  const StageTwoSummary s =
      optimizeStageTwo(&poses, models, priors, contacts, &ground.posed, StageTwoConfig());
  ASSERT_TRUE(s.solved);
  EXPECT_EQ(s.contacts, 2);
  EXPECT_NEAR(poses[0].translation().z(), bottom_true.translation().z(), 0.001);
  EXPECT_NEAR(poses[1].translation().z(), top_true.translation().z(), 0.001);
  // Level again.
  EXPECT_LT(std::acos((poses[0].linear() * Eigen::Vector3d::UnitZ()).z()), 0.2 * M_PI / 180);
  EXPECT_LT(std::acos((poses[1].linear() * Eigen::Vector3d::UnitZ()).z()), 0.2 * M_PI / 180);
  // In-plane position stays with the prior.
  EXPECT_NEAR(poses[1].translation().x(), 0.01, 0.002);
}

// The table of the separation tests (stage II's ground block, `Ground`, is at its height).
SupportPlane separationTable() {
  SupportPlane plane;
  plane.valid = true, plane.height = 0.75, plane.centre = Eigen::Vector3d(0, 0, 0.75);
  plane.size = Eigen::Vector2d(1.2, 0.8);
  return plane;
}

// Two 10 x 10 x 5 cm boxes of two classes (two of one class are left to merging).
std::pair<std::shared_ptr<ObjectModel>, std::shared_ptr<ObjectModel>> twoBoxes() {
  auto box = std::make_shared<ObjectModel>(boxModel(0.1, 0.1, 0.05));
  auto other = std::make_shared<ObjectModel>(boxModel(0.1, 0.1, 0.05));
  other->name = "other_box";
  return {box, other};
}

// The table and two boxes of two classes, with the collider that measures them.
class StageTwoPair : public ::testing::Test {
 protected:
  StageTwoPair() { std::tie(box, other) = twoBoxes(); }
  const Ground ground;
  const SupportPlane plane = separationTable();
  std::shared_ptr<ObjectModel> box, other;
  HullCollider collider;
};

// Two boxes side by side on the table, their estimates 6 mm into each other (side contacts stay
// out of stage II), and one 2 mm into the table: FCL finds both, the separation factors part
// them, and the table's supports keep them on it.
TEST_F(StageTwoPair, SeparationFactorsPartInterpenetratingEstimates) {
  const std::vector<Eigen::Isometry3d> priors = {at(0, 0, 0.775), at(0.094, 0, 0.773)};
  ASSERT_EQ(findInterpenetrations({{box, priors[0]}, {box, priors[1]}}, &plane,
                                  ground.posed.T_world_obj, 0.0005, &collider)
                .size(),
            1u);  // the table's only
  // The final solve (after the last merge) parts two of one class as well.
  EXPECT_EQ(findInterpenetrations({{box, priors[0]}, {box, priors[1]}}, &plane,
                                  ground.posed.T_world_obj, 0.0005, &collider, true)
                .size(),
            2u);
  const std::vector<Separation> found = findInterpenetrations(
      {{box, priors[0]}, {other, priors[1]}}, &plane, ground.posed.T_world_obj, 0.0005, &collider);
  ASSERT_EQ(found.size(), 2u);
  const Separation& pair = found[0].object_a == 0 ? found[0] : found[1];
  const Separation& table = found[0].object_a == 0 ? found[1] : found[0];
  EXPECT_EQ(pair.object_b, 1);
  EXPECT_NEAR(pair.depth, 0.006, 2e-4);
  EXPECT_GT(pair.normal.x(), 0.99);  // from a to b
  EXPECT_EQ(table.object_a, -1);
  EXPECT_EQ(table.object_b, 1);
  EXPECT_NEAR(table.depth, 0.002, 1e-6);
  EXPECT_NEAR(table.normal.z(), 1.0, 1e-9);
  std::vector<const ObjectModel*> models = {box.get(), other.get()};
  const auto contacts = inferRelations({{box.get(), priors[0]}, {other.get(), priors[1]}},
                                       &ground.posed, kGravity, ContactConfig());
  std::vector<Eigen::Isometry3d> poses = priors;
  const StageTwoSummary s =
      optimizeStageTwo(&poses, models, priors, contacts, &ground.posed, StageTwoConfig(), found);
  ASSERT_TRUE(s.solved);
  EXPECT_EQ(s.separations, 2);
  EXPECT_LT(collider.penetration(box, poses[0], other, poses[1]), 0.0002);
  EXPECT_GT(poses[1].translation().x() - poses[0].translation().x(), 0.0995);
  for (const Eigen::Isometry3d& T : poses) EXPECT_NEAR(T.translation().z(), 0.775, 3e-4);
  // A re-solve of part of the scene: the held box stays exactly where it was, the other box
  // alone parts from it and comes out of the table.
  poses = priors;
  const StageTwoSummary part = optimizeStageTwo(&poses, models, priors, contacts, &ground.posed,
                                                StageTwoConfig(), found, {true, false});
  ASSERT_TRUE(part.solved);
  EXPECT_TRUE(poses[0].isApprox(priors[0], 1e-12));
  EXPECT_LT(collider.penetration(box, poses[0], other, poses[1]), 0.0002);
  EXPECT_GT(poses[1].translation().x() - priors[0].translation().x(), 0.0995);
  EXPECT_NEAR(poses[1].translation().z(), 0.775, 3e-4);
  // Without them the pair stays as it was.
  poses = priors;
  optimizeStageTwo(&poses, models, priors, contacts, &ground.posed, StageTwoConfig());
  EXPECT_NEAR(collider.penetration(box, poses[0], other, poses[1]), 0.006, 5e-4);
}

// Issue 50: an object's prior weighs by its evidence (stage_two.prior_full_weight_measurements).
// The pair of the test above, one box measured 100 times, the other twice: parted, the one seen
// twice yields (weight sqrt(2 / 20): it moves about 10 times farther, as the weights' squares);
// with one weight for both they share the 6 mm.
TEST_F(StageTwoPair, AnObjectSeenTwiceYieldsToOneSeenOften) {
  const std::vector<Eigen::Isometry3d> priors = {at(0, 0, 0.775), at(0.094, 0, 0.775)};
  const std::vector<Separation> found = findInterpenetrations(
      {{box, priors[0]}, {other, priors[1]}}, &plane, ground.posed.T_world_obj, 0.0005, &collider);
  ASSERT_EQ(found.size(), 1u);
  const std::vector<const ObjectModel*> models = {box.get(), other.get()};
  const auto contacts = inferRelations({{box.get(), priors[0]}, {other.get(), priors[1]}},
                                       &ground.posed, kGravity, ContactConfig());
  StageTwoConfig config;
  config.prior_full_weight_measurements = 0;  // off: every object weight 1
  EXPECT_EQ(priorWeight(2, config), 1.0);
  config.prior_full_weight_measurements = 20;
  config.prior_min_weight = 0.2;
  EXPECT_EQ(priorWeight(100, config), 1.0);
  EXPECT_EQ(priorWeight(20, config), 1.0);
  EXPECT_NEAR(priorWeight(5, config), 0.5, 1e-12);
  EXPECT_EQ(priorWeight(0, config), 0.2);
  const std::vector<double> weights = {priorWeight(100, config), priorWeight(2, config)};
  std::vector<Eigen::Isometry3d> poses = priors;
  ASSERT_TRUE(
      optimizeStageTwo(&poses, models, priors, contacts, &ground.posed, config, found, {}, weights)
          .solved);
  EXPECT_LT(collider.penetration(box, poses[0], other, poses[1]), 0.0002);
  const double moved_often = (poses[0].translation() - priors[0].translation()).norm();
  const double moved_twice = (poses[1].translation() - priors[1].translation()).norm();
  std::printf("parted: seen 100 times moved %.2f mm, seen twice %.2f mm\n", 1000 * moved_often,
              1000 * moved_twice);
  EXPECT_LT(moved_often, 0.001);
  EXPECT_GT(moved_twice, 8 * moved_often);
  // One weight for both: each moves about half.
  poses = priors;
  ASSERT_TRUE(
      optimizeStageTwo(&poses, models, priors, contacts, &ground.posed, StageTwoConfig(), found)
          .solved);
  EXPECT_NEAR((poses[0].translation() - priors[0].translation()).norm(), 0.003, 0.001);
  // A weight that is no weight is refused, nothing moved.
  poses = priors;
  const StageTwoSummary bad = optimizeStageTwo(&poses, models, priors, contacts, &ground.posed,
                                               config, found, {}, {1.0, 0.0});
  EXPECT_EQ(bad.status, SolveStatus::kBadInput);
  EXPECT_TRUE(poses[1].isApprox(priors[1], 1e-12));
}

// A separation is carried to later keyframes while its pair still interpenetrates at the poses it
// is checked at (stage I's, stage_two.separation_drop_stale); once a new measurement has moved
// the estimates apart, it would only hold them off it.
TEST_F(StageTwoPair, ACarriedSeparationHoldsWhileItsPairStillInterpenetrates) {
  const std::vector<CollisionBody> found_at = {{box, at(0, 0, 0.775)},
                                               {other, at(0.094, 0, 0.773)}};
  const std::vector<Separation> found =
      findInterpenetrations(found_at, &plane, ground.posed.T_world_obj, 0.0005, &collider);
  ASSERT_EQ(found.size(), 2u);
  for (const Separation& s : found) {
    SCOPED_TRACE(s.object_a);
    EXPECT_TRUE(stillInterpenetrating(s, found_at, plane, 0.0005, &collider));
    // Measured again 1 mm apart and on the table: both separations are stale.
    const std::vector<CollisionBody> parted = {{box, at(0, 0, 0.775)},
                                               {other, at(0.101, 0, 0.775)}};
    EXPECT_FALSE(stillInterpenetrating(s, parted, plane, 0.0005, &collider));
  }
  // Still 2 mm into its neighbour (and out of the table): the pair's holds, the table's does not.
  const std::vector<CollisionBody> closer = {{box, at(0, 0, 0.775)}, {other, at(0.098, 0, 0.775)}};
  for (const Separation& s : found)
    EXPECT_EQ(stillInterpenetrating(s, closer, plane, 0.0005, &collider), s.object_a == 0);
}

// An L of two convex parts and a cube by its inner corner: the cube lies 2 mm inside the L's hull
// (which spans the corner) and clear of both arms. The physical check's bodies are the hulls,
// so the final solve parts so shallow a hull contact as hulls; a cube deep in the corner is in
// the L's hollow, not in the L, and only parts would part it (nothing here).
TEST(StageTwo, ShallowHullContactsArePartedAsHulls) {
  auto ell = std::make_shared<ObjectModel>();
  ell->name = "ell";
  auto arm = [](const Eigen::Vector3d& size, const Eigen::Vector3d& centre) {
    TriangleMesh m = makeBox(size);
    for (auto& v : m.vertices) v += centre.cast<float>();
    return m;
  };
  ell->collision_parts = {arm({0.2, 0.04, 0.04}, {0, 0, 0}),
                          arm({0.04, 0.2, 0.04}, {-0.08, 0.08, 0})};
  for (const TriangleMesh& part : ell->collision_parts) {
    const int offset = static_cast<int>(ell->mesh.vertices.size());
    ell->mesh.vertices.insert(ell->mesh.vertices.end(), part.vertices.begin(), part.vertices.end());
    for (Eigen::Vector3i t : part.triangles) ell->mesh.triangles.push_back(t.array() + offset);
  }
  const auto cube = std::make_shared<ObjectModel>(boxModel(0.03, 0.03, 0.03));
  // The hull's face over the corner: x + y = 0.12 (from the arms' ends (0.1, 0.02), (-0.06, 0.18)).
  auto cubeInside = [](double depth) {
    const double c = 0.5 * (0.15 - depth * std::sqrt(2.0));  // the cube's corner `depth` inside
    return at(c, c, 0.0);
  };
  HullCollider collider;
  for (double depth : {0.002, 0.010}) {
    SCOPED_TRACE(depth);
    const std::vector<CollisionBody> bodies = {{ell, at(0, 0, 0)}, {cube, cubeInside(depth)}};
    EXPECT_NEAR(collider.penetration(ell, at(0, 0, 0), cube, cubeInside(depth)), depth, 2e-4);
    EXPECT_EQ(collider.partsPenetration(ell, at(0, 0, 0), cube, cubeInside(depth)), 0.0);
    EXPECT_TRUE(findInterpenetrations(bodies, nullptr, at(0, 0, 0), 0.0005, &collider).empty());
    const std::vector<Separation> as_hulls =
        findInterpenetrations(bodies, nullptr, at(0, 0, 0), 0.0005, &collider, true, 0.003);
    if (depth > 0.003) {
      EXPECT_TRUE(as_hulls.empty());
      continue;
    }
    ASSERT_EQ(as_hulls.size(), 1u);
    EXPECT_NEAR(as_hulls[0].depth, depth, 2e-4);
    EXPECT_GT(as_hulls[0].normal.dot(Eigen::Vector3d(1, 1, 0).normalized()), 0.99);  // out of the L
  }
}

TEST(StageTwo, CanLyingOnABoxTouchesIt) {
  const Ground ground;
  const ObjectModel box = boxModel(0.2, 0.2, 0.1);
  const ObjectModel can = canModel(0.03, 0.1);
  // Box on the table; can lying on the box, 4 mm into it.
  std::vector<Eigen::Isometry3d> priors = {at(0, 0, 0.80),
                                           at(0, 0, 0.876, rot(90, Eigen::Vector3d::UnitX()))};
  std::vector<const ObjectModel*> models = {&box, &can};
  std::vector<PosedModel> posed = {{&box, priors[0]}, {&can, priors[1]}};
  const auto contacts = inferRelations(posed, &ground.posed, kGravity, ContactConfig());
  bool p2c = false;
  for (const auto& c : contacts) p2c |= c.type == ContactType::kPlaneCurve && c.object_b == 1;
  ASSERT_TRUE(p2c);
  std::vector<Eigen::Isometry3d> poses = priors;
  ASSERT_TRUE(
      optimizeStageTwo(&poses, models, priors, contacts, &ground.posed, StageTwoConfig()).solved);
  EXPECT_NEAR(poses[1].translation().z(), 0.85 + 0.03, 0.001);
}

// A clamp leaning on a can's rim, its estimate 4 mm into the rim: stage II's plane-edge factor
// moves it back onto the rim (no interpenetration, still in contact, still leaning).
TEST(StageTwo, ClampLeaningOnACanStaysInContactWithoutInterpenetration) {
  const Ground ground;
  const ObjectModel can = canModel(0.033, 0.1), clamp = boxModel(0.02, 0.08, 0.18);
  const double theta = 30.0 * M_PI / 180.0;
  const Eigen::Vector3d rim(0.033, 0, 0.85);
  const Eigen::Vector3d n(-std::cos(theta), 0, -std::sin(theta)),
      u(-std::sin(theta), 0, std::cos(theta));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = -n, T.linear().col(1) = Eigen::Vector3d::UnitY(), T.linear().col(2) = u;
  T.translation() = rim - n * (0.01 - 0.004) - u * 0.03;  // 4 mm into the rim
  std::vector<Eigen::Isometry3d> priors = {at(0, 0, 0.80), T};
  std::vector<const ObjectModel*> models = {&can, &clamp};
  const auto leaning = [&](const std::vector<Eigen::Isometry3d>& poses) {
    std::vector<FeatureContact> out;
    for (const FeatureContact& c : inferRelations({{&can, poses[0]}, {&clamp, poses[1]}},
                                                  &ground.posed, kGravity, ContactConfig()))
      if (c.kind == ContactKind::kLeaning) out.push_back(c);
    return out;
  };
  const auto before = leaning(priors);
  ASSERT_EQ(before.size(), 1u);
  EXPECT_EQ(before[0].type, ContactType::kPlaneEdge);
  EXPECT_NEAR(before[0].distance_residual, -0.004, 1e-4);
  std::vector<Eigen::Isometry3d> poses = priors;
  ASSERT_TRUE(optimizeStageTwo(&poses, models, priors,
                               inferRelations({{&can, priors[0]}, {&clamp, priors[1]}},
                                              &ground.posed, kGravity, ContactConfig()),
                               &ground.posed, StageTwoConfig())
                  .solved);
  const auto after = leaning(poses);
  ASSERT_EQ(after.size(), 1u);
  EXPECT_NEAR(after[0].distance_residual, 0.0, 5e-4);
  EXPECT_NEAR(poses[0].translation().z(), 0.80, 0.001);  // the can stays on the table
}

// The depth image of a table (top at 0.75 m) with a 10 x 10 x 20 cm box on it, seen from above
// its edge.
struct TableDepth {
  PinholeIntrinsics K;
  Eigen::Isometry3d T_map_cam = lookAt(Eigen::Vector3d(-0.9, 0.1, 1.35),
                                       Eigen::Vector3d(0, 0, 0.75), Eigen::Vector3d::UnitZ());
  RenderedImages out;
  DepthImageView depth() const { return {out.depth.data(), K.width, K.height}; }
};

TableDepth renderTableWithBox() {
  OffscreenRenderer renderer;
  TableDepth scene;
  const MeshHandle table = renderer.addMesh(makeBox(Eigen::Vector3d(1.2, 0.8, 0.04)));
  const MeshHandle box = renderer.addMesh(makeBox(Eigen::Vector3d(0.1, 0.1, 0.2)));
  const Eigen::Isometry3d T_cam_map = scene.T_map_cam.inverse();
  renderer.render(scene.K,
                  {{table, T_cam_map * at(0, 0, 0.73), 1}, {box, T_cam_map * at(0, 0, 0.85), 2}},
                  &scene.out, PixelBox{}, OffscreenRenderer::kDepth);
  return scene;
}

TEST(Relations, SupportPlaneFromRenderedDepth) {
  const TableDepth scene = renderTableWithBox();
  const auto& [K, T_map_cam] = std::tie(scene.K, scene.T_map_cam);
  const DepthImageView depth = scene.depth();
  const SupportPlane plane = estimateSupportPlane(depth, K, T_map_cam, kGravity);
  ASSERT_TRUE(plane.valid);
  EXPECT_NEAR(plane.height, 0.75, 0.003);
  EXPECT_GT(plane.normal.z(), 0.999);
  EXPECT_GT(plane.size.x(), 0.3);
  // Fused with a second estimate, it stays there.
  SupportPlane fused;
  fuseSupportPlane(plane, &fused);
  fuseSupportPlane(plane, &fused);
  EXPECT_NEAR(fused.height, 0.75, 0.003);
  // No depth, no plane.
  std::vector<float> empty(static_cast<std::size_t>(K.width * K.height), 0.f);
  EXPECT_FALSE(
      estimateSupportPlane({empty.data(), K.width, K.height}, K, T_map_cam, kGravity).valid);
}

// How far an estimate reaches through the table top (the estimator lifts one deeper than the
// contacts reach: stage_two.lift_out_of_support).
TEST(Relations, DepthThroughTheSupportPlane) {
  const TableDepth scene = renderTableWithBox();
  const SupportPlane plane =
      estimateSupportPlane(scene.depth(), scene.K, scene.T_map_cam, kGravity);
  ASSERT_TRUE(plane.valid);
  ObjectModel box;
  box.mesh = makeBox(Eigen::Vector3d(0.1, 0.1, 0.2));
  // Resting on it, 5 cm into it, tipped 90 degrees and 4 cm into it.
  EXPECT_LT(depthThroughPlane(plane, box, at(0.2, 0.1, 0.85)), 0.004);
  EXPECT_NEAR(depthThroughPlane(plane, box, at(0.2, 0.1, 0.80)), 0.05, 0.004);
  Eigen::Isometry3d tipped = at(0.2, -0.1, 0.76);
  tipped.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  EXPECT_NEAR(depthThroughPlane(plane, box, tipped), 0.04, 0.004);
  // Beside the table (on the floor, 2 m away): nothing to do with this plane.
  EXPECT_EQ(depthThroughPlane(plane, box, at(2.5, 0.1, 0.3)), 0.0);
  // No plane, no depth.
  EXPECT_EQ(depthThroughPlane(SupportPlane{}, box, at(0.2, 0.1, 0.80)), 0.0);
}

TEST(Relations, AKnownSupportPlaneIsFollowedOrSearchedAgain) {
  const TableDepth scene = renderTableWithBox();
  const auto& [K, T_map_cam] = std::tie(scene.K, scene.T_map_cam);
  const DepthImageView depth = scene.depth();
  const SupportPlane searched = estimateSupportPlane(depth, K, T_map_cam, kGravity);
  ASSERT_TRUE(searched.valid);

  // A known plane 6 mm high and tilted by half a degree: followed onto the table's top.
  SupportPlane known = searched;
  known.height += 0.006;
  known.normal = Eigen::AngleAxisd(0.5 * M_PI / 180.0, Eigen::Vector3d::UnitX()) * known.normal;
  const SupportPlane followed =
      estimateSupportPlane(depth, K, T_map_cam, kGravity, SupportPlaneConfig(), &known);
  ASSERT_TRUE(followed.valid);
  EXPECT_NEAR(followed.height, 0.75, 0.002);
  EXPECT_GT(followed.normal.z(), 0.9999);
  EXPECT_NEAR(followed.inliers, searched.inliers, 0.02 * searched.inliers);
  EXPECT_NEAR(followed.size.x(), searched.size.x(), 0.02);

  // Known planes with too few points near them (the floor, the box's small top): searched again.
  for (double height : {0.0, 0.95}) {
    known = searched;
    known.height = height;
    const SupportPlane again =
        estimateSupportPlane(depth, K, T_map_cam, kGravity, SupportPlaneConfig(), &known);
    ASSERT_TRUE(again.valid) << height;
    EXPECT_NEAR(again.height, 0.75, 0.003) << height;
  }
}

TEST(Relations, AKnownTableIsFollowedWhereTheFloorDominates) {
  // A small table over a floor that fills most of the view: RANSAC finds the floor, following
  // the known table keeps the table; a known plane that used to have far more points than are
  // near it now is searched for again.
  OffscreenRenderer renderer;
  const MeshHandle floor = renderer.addMesh(makeBox(Eigen::Vector3d(8.0, 8.0, 0.04)));
  const MeshHandle table = renderer.addMesh(makeBox(Eigen::Vector3d(0.7, 0.5, 0.04)));
  const PinholeIntrinsics K;
  const Eigen::Isometry3d T_map_cam =
      lookAt(Eigen::Vector3d(-1.2, 0.0, 1.6), Eigen::Vector3d(0, 0, 0.3), Eigen::Vector3d::UnitZ());
  const Eigen::Isometry3d T_cam_map = T_map_cam.inverse();
  RenderedImages out;
  ASSERT_TRUE(renderer.render(
      K, {{floor, T_cam_map * at(0, 0, -0.02), 1}, {table, T_cam_map * at(0, 0, 0.73), 2}}, &out,
      PixelBox{}, OffscreenRenderer::kDepth));
  const DepthImageView depth{out.depth.data(), K.width, K.height};
  const SupportPlane searched = estimateSupportPlane(depth, K, T_map_cam, kGravity);
  ASSERT_TRUE(searched.valid);
  ASSERT_NEAR(searched.height, 0.0, 0.003);  // the scene is as meant: the floor dominates

  SupportPlane known;
  known.valid = true;
  known.height = 0.745;
  known.inliers = 1000;
  known.observations = 1;
  const SupportPlane followed =
      estimateSupportPlane(depth, K, T_map_cam, kGravity, SupportPlaneConfig(), &known);
  ASSERT_TRUE(followed.valid);
  EXPECT_NEAR(followed.height, 0.75, 0.002);
  EXPECT_GT(followed.inliers, SupportPlaneConfig().min_inliers);
  EXPECT_LT(followed.inliers, searched.inliers);

  known.inliers = 4 * followed.inliers;  // it used to have twice as many and more: search
  EXPECT_NEAR(
      estimateSupportPlane(depth, K, T_map_cam, kGravity, SupportPlaneConfig(), &known).height, 0.0,
      0.003);
}

TEST(Relations, NearbyButNotTouchingGivesNothing) {
  const Ground ground;
  const ObjectModel box = boxModel(0.1, 0.1, 0.1);
  // Two boxes on the table 2 cm apart: only the two table contacts.
  std::vector<PosedModel> posed = {{&box, at(0, 0, 0.80)}, {&box, at(0.12, 0, 0.80)}};
  auto contacts = inferRelations(posed, &ground.posed, kGravity, ContactConfig());
  ASSERT_EQ(contacts.size(), 2u);
  for (const auto& c : contacts) EXPECT_EQ(c.object_a, -1);
  // A box floating 2 cm above the table: nothing.
  posed = {{&box, at(0, 0, 0.82)}};
  EXPECT_TRUE(inferRelations(posed, &ground.posed, kGravity, ContactConfig()).empty());
}

TEST(Relations, CansSideBySideTouchCurveToCurve) {
  const Ground ground;
  const ObjectModel can = canModel(0.033, 0.1);
  // Two cans lying along x on the table, side by side, 1 mm apart.
  const Eigen::Matrix3d lying = rot(90, Eigen::Vector3d::UnitY());
  std::vector<PosedModel> posed = {{&can, at(0, 0, 0.783, lying)},
                                   {&can, at(0, 0.067, 0.783, lying)}};
  ContactConfig all;
  all.support_only = false;
  int c2c = 0, on_table = 0;
  for (const auto& c : inferRelations(posed, &ground.posed, kGravity, all)) {
    if (c.object_a == -1) {
      ++on_table;
      EXPECT_EQ(c.type, ContactType::kPlaneCurve);
    } else {
      ++c2c;
      EXPECT_EQ(c.type, ContactType::kCurveCurve);
      EXPECT_FALSE(c.support());
      EXPECT_NEAR(std::abs(c.normal.y()), 1.0, 1e-3);
    }
  }
  EXPECT_EQ(on_table, 2);
  EXPECT_EQ(c2c, 1);
  // Support only (the paper's stage II): the side contact is not a support.
  ContactConfig support_only;
  support_only.support_only = true;
  for (const auto& c : inferRelations(posed, &ground.posed, kGravity, support_only))
    EXPECT_EQ(c.object_a, -1);
}

TEST(Relations, TouchingVerticalFacesAreNoSupport) {
  const Ground ground;
  const ObjectModel box = boxModel(0.1, 0.1, 0.1);
  // Two boxes on the table, side faces 1 mm apart: two table supports and a side contact.
  std::vector<PosedModel> posed = {{&box, at(0, 0, 0.80)}, {&box, at(0.101, 0, 0.80)}};
  const auto contacts = inferRelations(posed, &ground.posed, kGravity, ContactConfig());
  ASSERT_EQ(contacts.size(), 3u);
  for (const auto& c : contacts) {
    EXPECT_EQ(c.object_a == -1, c.support());
    if (!c.support()) {
      EXPECT_EQ(c.kind, ContactKind::kSide);
    }
  }
}

}  // namespace
}  // namespace geofusion
