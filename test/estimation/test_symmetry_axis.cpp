// Issue 51: the angle about a can's axis follows its detections where they agree. Unit cases of
// the circular statistics, then the estimator end to end on a generated clutter sequence whose
// cans carry a label (appearance symmetry none): a can measured at a fixed angle about its axis
// keeps it through stage I and stage II; an untextured can's axis stays free.
#include "demo_sequence.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/estimation/symmetry_axis.h"
#include "geofusion/evaluation/evaluation.h"
#include "geofusion/simulation/dataset.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

namespace geofusion {
namespace {

constexpr double kDeg = M_PI / 180.0;

ObjectModel can(const Symmetry& appearance) {
  ObjectModel m = *ModelSet::builtinPrimitives().find("007_tuna_fish_can");
  m.appearance_symmetry = appearance;
  return m;
}

Symmetry halfTurnAboutZ() {
  Symmetry s;
  s.type = Symmetry::Type::kDiscrete;
  s.rotations.emplace_back(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()));
  return s;
}

// Rotations of a can tilted by `tilt` and turned about its axis by `angle` + noise.
std::vector<AxialSample> samplesAt(double angle, double noise, int n, unsigned seed,
                                   bool half_turns = false) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, noise);
  std::uniform_int_distribution<int> coin(0, 1);
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
  std::vector<AxialSample> out;
  for (int i = 0; i < n; ++i) {
    const double a = angle + gauss(rng) + (half_turns && coin(rng) ? M_PI : 0.0);
    out.push_back({tilt * Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(), 1.0});
  }
  return out;
}

// The angle R is turned about z from R_reference (R = R_reference Rot(z, angle) for a pure turn).
double angleAboutZ(const Eigen::Matrix3d& R_reference, const Eigen::Matrix3d& R) {
  return axialOffset(Eigen::Vector3d::UnitZ(), R, R_reference);
}

TEST(SymmetryAxis, WhoseAxisTheDetectorSees) {
  EXPECT_TRUE(axisSeenByDetector(can(Symmetry())));
  EXPECT_TRUE(axisSeenByDetector(can(halfTurnAboutZ())));
  EXPECT_FALSE(axisSeenByDetector(can(can(Symmetry()).symmetry)));  // untextured: shape = looks
  const ModelSet primitives = ModelSet::builtinPrimitives();
  EXPECT_FALSE(axisSeenByDetector(*primitives.find("003_cracker_box")));
  EXPECT_EQ(orderAbout(halfTurnAboutZ(), Eigen::Vector3d::UnitZ()), 2);
  EXPECT_EQ(orderAbout(halfTurnAboutZ(), Eigen::Vector3d::UnitX()), 1);
  EXPECT_EQ(orderAbout(Symmetry(), Eigen::Vector3d::UnitZ()), 1);
}

TEST(SymmetryAxis, AgreeingDetectionsGiveTheirCircularMean) {
  const ObjectModel m = can(Symmetry());
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const AxialAgreement a = axialAgreement(m, tilt, samplesAt(70 * kDeg, 3 * kDeg, 40, 1));
  EXPECT_EQ(a.samples, 40);
  EXPECT_GT(a.resultant, 0.99);
  const Eigen::Matrix3d turned = turnedToAgreement(m, tilt, a);
  EXPECT_NEAR(angleAboutZ(tilt, turned), 70 * kDeg, 1.5 * kDeg);
  // Near the wrap: -175 and +175 degrees average to 180, not 0.
  const AxialAgreement wrap = axialAgreement(m, tilt, samplesAt(M_PI, 5 * kDeg, 40, 2));
  EXPECT_NEAR(std::abs(angleAboutZ(tilt, turnedToAgreement(m, tilt, wrap))), M_PI, 2 * kDeg);
}

TEST(SymmetryAxis, ScatteredDetectionsDoNotAgree) {
  const ObjectModel m = can(Symmetry());
  const AxialAgreement a =
      axialAgreement(m, Eigen::Matrix3d::Identity(), samplesAt(0.0, 180 * kDeg, 60, 3));
  EXPECT_LT(a.resultant, 0.3);
  EXPECT_GT(a.spread_rad, 80 * kDeg);
}

TEST(SymmetryAxis, AHalfTurnSymmetricLabelAgreesModuloHalfTurns) {
  // Detections 30 degrees and 210 degrees: the same look for a master chef can (BOP: one
  // 180-degree symmetry), two opposite angles for a tuna fish can.
  const std::vector<AxialSample> s = samplesAt(30 * kDeg, 3 * kDeg, 40, 4, true);
  const AxialAgreement half = axialAgreement(can(halfTurnAboutZ()), Eigen::Matrix3d::Identity(), s);
  EXPECT_EQ(half.order, 2);
  EXPECT_GT(half.resultant, 0.98);
  const double mean = std::remainder(half.mean_rad - (-30 * kDeg), M_PI);  // offsets are -angle
  EXPECT_NEAR(mean, 0.0, 2 * kDeg);
  const AxialAgreement none = axialAgreement(can(Symmetry()), Eigen::Matrix3d::Identity(), s);
  EXPECT_LT(none.resultant, 0.5);
}

TEST(SymmetryAxis, BadSamplesAreLeftOut) {
  std::vector<AxialSample> s = samplesAt(10 * kDeg, 1 * kDeg, 5, 5);
  s.push_back({Eigen::Matrix3d::Constant(std::nan("")), 1.0});
  s.push_back({Eigen::Matrix3d::Identity(), 0.0});
  const AxialAgreement a = axialAgreement(can(Symmetry()), Eigen::Matrix3d::Identity(), s);
  EXPECT_EQ(a.samples, 5);
  EXPECT_TRUE(std::isfinite(a.mean_rad));
  EXPECT_EQ(axialAgreement(can(Symmetry()), Eigen::Matrix3d::Identity(), {}).samples, 0);
}

// The demo suite's first scene with the primitives' cans labelled (appearance none), 40
// keyframes; every detection of a can turned to `offset` about its axis from the truth (its tilt
// noise kept).
using LabelledCans = DemoSequence;

const LabelledCans& labelledCans() {
  static LabelledCans* s = [] {
    ModelSet labelled;
    const ModelSet primitives = ModelSet::builtinPrimitives();
    for (const auto& m : primitives.models()) {
      ObjectModel copy = *m;
      if (copy.symmetry.type == Symmetry::Type::kContinuous) copy.appearance_symmetry = Symmetry();
      labelled.add(std::move(copy));
    }
    return makeDemoSequence(std::move(labelled), 10, 0.3);
  }();
  return *s;
}

// Largest angle about the axis between each mapped can and its truth turned by `offset`, over
// the cans mapped (matched to the nearest true object of their class within 5 cm).
double worstCanAngle(double offset, bool axis_from_detections, int* cans) {
  const LabelledCans& s = labelledCans();
  EstimatorConfig config;
  config.method = Method::kGeoFusion;
  config.stage_one.axis_from_detections = axis_from_detections;
  SceneEstimator estimator(s.models, config);
  std::mt19937 rng(11);
  std::normal_distribution<double> axial_noise(0.0, 5.0 * kDeg);  // a detector's about the axis
  for (std::size_t k = 0; k < s.frames.size(); ++k) {
    Keyframe kf = makeKeyframe(s.poses[k], s.frames[k], PinholeIntrinsics());
    const Eigen::Isometry3d T_cam_world = s.poses[k].T_map_optical.inverse();
    for (std::size_t d = 0; d < kf.detections.size(); ++d) {
      const int truth = s.frames[k].detection_truth[d];
      if (truth < 0) continue;
      const SceneObject& o = s.scene.objects[static_cast<std::size_t>(truth)];
      if (!axisSeenByDetector(*o.model) || o.model->name != kf.detections[d].class_name) continue;
      const Eigen::Vector3d a = o.model->symmetry.axis;
      const Eigen::Matrix3d R_ref =
          (T_cam_world * o.T_world_obj).linear() * Eigen::AngleAxisd(offset, a).toRotationMatrix();
      Eigen::Isometry3d& T = kf.detections[d].T_cam_obj;
      const Eigen::Matrix3d R = T.linear();
      T.linear() =
          R * Eigen::AngleAxisd(axialOffset(a, R_ref, R) + axial_noise(rng), a).toRotationMatrix();
    }
    estimator.addKeyframe(kf);
  }
  const KeyframeResult final = estimator.finish();
  double worst = 0.0;
  *cans = 0;
  for (const ObjectEstimate& e : final.objects) {
    if (!axisSeenByDetector(*e.model)) continue;
    const SceneObject* best = nullptr;
    for (const SceneObject& o : s.scene.objects)
      if (o.model->name == e.model->name &&
          (o.T_world_obj.translation() - e.T_map_obj.translation()).norm() < 0.05 &&
          (!best || (o.T_world_obj.translation() - e.T_map_obj.translation()).norm() <
                        (best->T_world_obj.translation() - e.T_map_obj.translation()).norm()))
        best = &o;
    if (!best) continue;
    const Eigen::Vector3d a = e.model->symmetry.axis;
    const Eigen::Matrix3d R_ref =
        best->T_world_obj.linear() * Eigen::AngleAxisd(offset, a).toRotationMatrix();
    const double angle = std::abs(axialOffset(a, R_ref, e.T_map_obj.linear()));
    std::printf("  %s: %.1f deg from the measured angle\n", e.model->name.c_str(), angle / kDeg);
    worst = std::max(worst, angle);
    ++*cans;
  }
  return worst;
}

// Each detection of a labelled can turned to `offset` about its axis from the truth, with 5
// degrees of noise about it: the map keeps the measured angle within 5 degrees; with the axis
// left free (stage_one.axis_from_detections off) it is printed for comparison.
TEST(SymmetryAxis, ACanMeasuredAtAFixedAngleKeepsItThroughStageOneAndTwo) {
  for (double offset : {0.0, 40 * kDeg, -110 * kDeg}) {
    int cans = 0, free_cans = 0;
    const double worst = worstCanAngle(offset, true, &cans);
    const double free = worstCanAngle(offset, false, &free_cans);
    std::printf(
        "measured %.0f deg off the truth: %d cans mapped, worst %.1f deg from it (axis "
        "free: %.1f deg)\n",
        offset / kDeg, cans, worst / kDeg, free / kDeg);
    EXPECT_GE(cans, 2);
    EXPECT_LT(worst, 5 * kDeg) << "offset " << offset / kDeg;
  }
}

}  // namespace
}  // namespace geofusion
