// Sequences: trajectory, depth noise, detection noise calibration, odometry drift.
#include "geofusion/evaluation/metrics.h"
#include "geofusion/evaluation/sequence_calibration.h"
#include "geofusion/simulation/dataset.h"
#include "geofusion/simulation/sequence.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

namespace geofusion {
namespace {

TEST(Metrics, AddAndAddsOnKnownPoses) {
  const std::vector<Eigen::Vector3f> pts = sampleSurfacePoints(makeCylinder(0.03, 0.1), 2000);
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity(), est = truth;
  est.translation().x() = 0.01;
  EXPECT_NEAR(addError(pts, est, truth), 0.01, 1e-9);
  const double adds = addsError(pts, est, truth);  // the surface partly slides onto itself
  EXPECT_GT(adds, 0.003);
  EXPECT_LT(adds, 0.01);
  // A rotation about the symmetry axis: ADD large, ADD-S nearly zero.
  est = truth;
  est.linear() = Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_GT(addError(pts, est, truth), 0.02);
  EXPECT_LT(addsError(pts, est, truth), 0.002);
  EXPECT_NEAR(accuracyAuc({0.0, 0.05, 0.2}), (100.0 + 50.0 + 0.0) / 3.0, 1e-9);
  EXPECT_NEAR(shareBelow({0.01, 0.03}, 0.02), 0.5, 1e-12);
}

class SequenceTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    models_ = new ModelSet(ModelSet::builtinPrimitives());
    scene_ = new ClutterScene();
    ClutterConfig config;
    config.num_objects = 12;
    std::string report;
    ASSERT_TRUE(makeClutterScene(*models_, config, 21, scene_, &report)) << report;
  }
  static void TearDownTestSuite() {
    delete scene_;
    delete models_;
  }
  static ModelSet* models_;
  static ClutterScene* scene_;
};
ModelSet* SequenceTest::models_ = nullptr;
ClutterScene* SequenceTest::scene_ = nullptr;

TEST_F(SequenceTest, TrajectoryCirclesTheTableLookingAtTheClutter) {
  TrajectoryConfig config;
  config.frames = 120;
  const auto poses = makeTrajectory(*scene_, config, 3);
  ASSERT_EQ(poses.size(), 120u);
  int paused = 0;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const auto& p = poses[k];
    const double h = p.T_map_optical.translation().z();
    EXPECT_GE(h, config.min_height_m - 1e-9);
    EXPECT_LE(h, config.max_height_m + 1e-9);
    const double d = p.T_map_base.translation().head<2>().norm();
    EXPECT_GT(d, 0.6);
    EXPECT_LT(d, 1.3);
    // The optical axis points down at the table centre region.
    const Eigen::Vector3d z = p.T_map_optical.linear().col(2);
    EXPECT_LT(z.z(), -0.25);
    // The optical frame agrees with the TF chain base -> link -> optical.
    EXPECT_TRUE((p.T_map_base * p.T_base_link * RobotGeometry::cameraLinkToOptical())
                    .isApprox(p.T_map_optical, 1e-9));
    if (k > 0 &&
        (poses[k].T_map_base.translation() - poses[k - 1].T_map_base.translation()).norm() < 1e-9)
      ++paused;
  }
  EXPECT_GE(paused, 10);  // pauses
  EXPECT_TRUE(
      makeTrajectory(*scene_, config, 3)[77].T_map_optical.isApprox(poses[77].T_map_optical));
}

TEST_F(SequenceTest, OdometryDriftsAFewCentimetres) {
  TrajectoryConfig config;
  config.frames = 200;
  std::vector<double> finals;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    auto poses = makeTrajectory(*scene_, config, seed);
    addOdometryDrift(&poses, OdometryNoise(), seed);
    const DriftStats s = measureDrift(poses);
    EXPECT_GT(s.path_length_m, 1.5);
    // A real robot's drift over a table-sized loop (ORB-SLAM2 on TUM desk: 1-2 cm).
    EXPECT_GT(s.max_m, 0.005);
    EXPECT_LT(s.max_m, 0.025);
    finals.push_back(s.max_m);
    std::cout << "drift: path " << s.path_length_m << " m, max " << s.max_m * 100 << " cm\n";
  }
  double mean = 0;
  for (double f : finals) mean += f / finals.size();
  EXPECT_GT(mean, 0.005);
  EXPECT_LT(mean, 0.03);
}

TEST_F(SequenceTest, FramesHaveNoisyDepthAndCalibratedDetections) {
  TrajectoryConfig config;
  config.frames = 30;
  const auto poses = makeTrajectory(*scene_, config, 4);
  SequenceRenderer renderer(*scene_, PinholeIntrinsics());
  ASSERT_TRUE(renderer.ok());
  std::mt19937 rng(9);
  SequenceCalibration calibration;
  for (const auto& pose : poses) {
    const SequenceFrame f =
        renderer.render(pose, DepthNoise(), DetectorModel::denseFusion(), *models_, rng);
    ASSERT_EQ(f.images.rgb.size(), 640u * 480u * 3u);
    ASSERT_EQ(f.detections.size(), f.detection_truth.size());
    calibration.add(*scene_, pose.T_map_optical, f);
  }
  std::cout << calibration.report();
  const auto all = calibration.overall();
  EXPECT_GT(calibration.detections(), 150);
  EXPECT_GT(calibration.falsePositives(), 2);
  EXPECT_NEAR(all.auc, 93.0, 3.0);
  EXPECT_NEAR(all.below_2cm, 0.97, 0.03);
  // Misses grow with occlusion: some, not most.
  EXPECT_GT(calibration.missed(), 0);
  EXPECT_LT(calibration.missed(), calibration.detectable() / 3);
  EXPECT_GT(calibration.depthNoiseRms(), 0.001);
  EXPECT_LT(calibration.depthNoiseRms(), 0.006);
  EXPECT_GT(calibration.holeShare(), 0.005);
  EXPECT_LT(calibration.holeShare(), 0.15);

  // The harsher PoseCNN-like preset on the same views. Its YCB-Video target is ADD-S AUC 75.9
  // (measured on the bench suite: 78.4, docs/dataset.md); these primitives have no clamps,
  // scissors or markers, which pull the YCB figure down, so here it is about 85.
  SequenceCalibration harsh;
  std::mt19937 rng2(9);
  for (const auto& pose : poses) {
    harsh.add(*scene_, pose.T_map_optical,
              renderer.render(pose, DepthNoise(), DetectorModel::posecnn(), *models_, rng2));
  }
  std::cout << "PoseCNN-like:\n" << harsh.report();
  EXPECT_LT(harsh.overall().auc, all.auc - 7.0);
  EXPECT_GT(harsh.overall().auc, 75.0);
  EXPECT_LT(harsh.overall().below_2cm, 0.85);
}

}  // namespace
}  // namespace geofusion
