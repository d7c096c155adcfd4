#include "geofusion/common/pose_validation.h"
#include "geofusion/estimation/frame_by_frame.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace geofusion {
namespace {

RawDetection good(const std::string& cls = "003_cracker_box") {
  RawDetection d;
  d.class_name = cls;
  d.class_id = 2;
  d.score = 0.9;
  d.position_cam = Eigen::Vector3d(0.1, -0.05, 0.8);
  d.orientation_cam =
      Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()));
  return d;
}

TEST(PoseValidation, ClassifiesEveryKindOfBadPose) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const Eigen::Quaterniond unit = Eigen::Quaterniond::Identity();
  EXPECT_EQ(checkPose(Eigen::Vector3d(1, 2, 3), unit), PoseStatus::kValid);
  EXPECT_EQ(checkPose(Eigen::Vector3d(nan, 0, 0), unit), PoseStatus::kNonFiniteTranslation);
  EXPECT_EQ(checkPose(Eigen::Vector3d(0, inf, 0), unit), PoseStatus::kNonFiniteTranslation);
  EXPECT_EQ(checkPose(Eigen::Vector3d::Zero(), Eigen::Quaterniond(nan, 0, 0, 0)),
            PoseStatus::kNonFiniteRotation);
  EXPECT_EQ(checkPose(Eigen::Vector3d::Zero(), Eigen::Quaterniond(0, 0, 0, 0)),
            PoseStatus::kZeroQuaternion);
  EXPECT_EQ(checkPose(Eigen::Vector3d::Zero(), Eigen::Quaterniond(2, 0, 0, 0)),
            PoseStatus::kNonUnitQuaternion);
  // float32 round-off of a unit quaternion is accepted.
  EXPECT_EQ(checkPose(Eigen::Vector3d::Zero(), Eigen::Quaterniond(0.5f, 0.5f, 0.5f, 0.5000001f)),
            PoseStatus::kValid);
}

TEST(FrameByFrame, PlacesDetectionsInTheWorldThroughTheCameraPose) {
  FrameByFrame fbf;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  T_world_cam.linear() = Eigen::AngleAxisd(-2.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  T_world_cam.translation() = Eigen::Vector3d(1.0, 0.5, 1.3);
  DetectionTally tally;
  const RawDetection d = good();
  const auto out = fbf.process({d}, T_world_cam, &tally);
  ASSERT_EQ(out.size(), 1u);
  const Eigen::Vector3d expected = T_world_cam * d.position_cam;
  EXPECT_LT((out[0].T_world_obj.translation() - expected).norm(), 1e-12);
  const Eigen::Matrix3d expected_R = T_world_cam.linear() * d.orientation_cam.toRotationMatrix();
  EXPECT_LT((out[0].T_world_obj.linear() - expected_R).norm(), 1e-12);
  EXPECT_EQ(tally.frames, 1u);
  EXPECT_EQ(tally.accepted, 1u);
  EXPECT_EQ(tally.totalSkipped(), 0u);
}

TEST(FrameByFrame, SkipsMalformedDetectionsAndKeepsTheRest) {
  FrameByFrame::Config cfg;
  cfg.min_score = 0.3;
  cfg.max_range_m = 3.0;
  FrameByFrame fbf(cfg);
  std::vector<RawDetection> in;
  in.push_back(good());
  RawDetection nan_pos = good();
  nan_pos.position_cam.x() = std::numeric_limits<double>::quiet_NaN();
  in.push_back(nan_pos);
  RawDetection nan_q = good();
  nan_q.orientation_cam.w() = std::numeric_limits<double>::quiet_NaN();
  in.push_back(nan_q);
  RawDetection zero_q = good();
  zero_q.orientation_cam = Eigen::Quaterniond(0, 0, 0, 0);
  in.push_back(zero_q);
  RawDetection non_unit = good();
  non_unit.orientation_cam = Eigen::Quaterniond(1, 1, 0, 0);
  in.push_back(non_unit);
  RawDetection empty_class = good("");
  in.push_back(empty_class);
  RawDetection low = good();
  low.score = 0.1;
  in.push_back(low);
  RawDetection bad_score = good();
  bad_score.score = 1.5;
  in.push_back(bad_score);
  RawDetection far = good();
  far.position_cam = Eigen::Vector3d(0, 0, 5.0);
  in.push_back(far);
  in.push_back(good("004_sugar_box"));

  DetectionTally tally;
  const auto out = fbf.process(in, Eigen::Isometry3d::Identity(), &tally);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].measurement.class_name, "003_cracker_box");
  EXPECT_EQ(out[1].measurement.class_name, "004_sugar_box");
  EXPECT_EQ(tally.accepted, 2u);
  EXPECT_EQ(tally.totalSkipped(), 8u);
  auto skipped = [&tally](SkipReason r) { return tally.skipped[static_cast<std::size_t>(r)]; };
  EXPECT_EQ(skipped(SkipReason::kNonFiniteTranslation), 1u);
  EXPECT_EQ(skipped(SkipReason::kNonFiniteRotation), 1u);
  EXPECT_EQ(skipped(SkipReason::kZeroQuaternion), 1u);
  EXPECT_EQ(skipped(SkipReason::kNonUnitQuaternion), 1u);
  EXPECT_EQ(skipped(SkipReason::kEmptyClass), 1u);
  EXPECT_EQ(skipped(SkipReason::kLowScore), 1u);
  EXPECT_EQ(skipped(SkipReason::kBadScore), 1u);
  EXPECT_EQ(skipped(SkipReason::kOutOfRange), 1u);
  // The accepted rotation is a proper rotation even though it came through float round-off.
  EXPECT_NEAR(out[0].T_world_obj.linear().determinant(), 1.0, 1e-12);
  EXPECT_NE(tally.summary().find("1 non-unit quaternion"), std::string::npos) << tally.summary();
}

TEST(DetectionTally, AddsUp) {
  DetectionTally a, b;
  a.frames = 2;
  a.accepted = 3;
  a.skipped[0] = 1;
  b.frames = 1;
  b.accepted = 4;
  b.skipped[0] = 2;
  a.add(b);
  EXPECT_EQ(a.frames, 3u);
  EXPECT_EQ(a.accepted, 7u);
  EXPECT_EQ(a.totalSkipped(), 3u);
}

// A detector gone wild (thousands of detections in a frame): the highest scores are kept up to
// the cap, in their order, and the rest counted; unknown classes are counted, not used.
TEST(FrameByFrame, CapsDetectionsByScoreAndCountsUnknownClasses) {
  FrameByFrame::Config cfg;
  cfg.max_detections = 3;
  FrameByFrame fbf(cfg);
  fbf.setKnownClasses({"003_cracker_box"});
  std::vector<RawDetection> in;
  for (double score : {0.2, 0.9, 0.5, 0.7, 0.1, 0.95}) {
    RawDetection d = good();
    d.score = score;
    in.push_back(d);
  }
  in.push_back(good("999_not_a_model"));
  DetectionTally tally;
  const auto out = fbf.process(in, Eigen::Isometry3d::Identity(), &tally);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_DOUBLE_EQ(out[0].measurement.score, 0.9);
  EXPECT_DOUBLE_EQ(out[1].measurement.score, 0.7);
  EXPECT_DOUBLE_EQ(out[2].measurement.score, 0.95);
  EXPECT_EQ(tally.accepted, 3u);
  EXPECT_EQ(tally.skipped[static_cast<std::size_t>(SkipReason::kOverCap)], 3u);
  EXPECT_EQ(tally.skipped[static_cast<std::size_t>(SkipReason::kUnknownClass)], 1u);
  EXPECT_NE(tally.summary().find("1 unknown class"), std::string::npos) << tally.summary();
  EXPECT_NE(tally.summary().find("3 over max_detections"), std::string::npos) << tally.summary();
  // 5000 detections in one frame: still the cap, quickly.
  std::vector<RawDetection> flood(5000, good());
  for (std::size_t i = 0; i < flood.size(); ++i) flood[i].score = 0.5 + 0.4 * (i % 100) / 100.0;
  cfg.max_detections = 100;
  fbf.setConfig(cfg);
  DetectionTally flood_tally;
  const auto kept = fbf.process(flood, Eigen::Isometry3d::Identity(), &flood_tally);
  ASSERT_EQ(kept.size(), 100u);
  for (const WorldDetection& d : kept) EXPECT_GE(d.measurement.score, 0.5 + 0.4 * 98 / 100.0);
  EXPECT_EQ(flood_tally.skipped[static_cast<std::size_t>(SkipReason::kOverCap)], 4900u);
}

}  // namespace
}  // namespace geofusion
