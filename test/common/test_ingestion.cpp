#include "geofusion/common/ingestion.h"

#include <gtest/gtest.h>

#include <cmath>

namespace geofusion {
namespace {

TEST(OdometryTimeline, TellsTheGapAroundAStamp) {
  OdometryTimeline odometry;
  EXPECT_TRUE(std::isinf(odometry.gapAround(1.0)));
  for (double t = 0.0; t < 1.001; t += 0.1) odometry.add(t);
  odometry.add(6.0);  // five seconds without odometry
  odometry.add(6.1);
  ASSERT_EQ(odometry.size(), 13u);
  EXPECT_NEAR(odometry.gapAround(0.55), 0.1, 1e-9);
  EXPECT_DOUBLE_EQ(odometry.gapAround(0.5), 0.0);
  EXPECT_NEAR(odometry.gapAround(3.0), 5.0, 1e-9);
  EXPECT_TRUE(std::isinf(odometry.gapAround(-1.0)));  // nothing before
  // None after yet: at least the time since the last sample.
  EXPECT_NEAR(odometry.gapAround(6.15), 0.05, 1e-9);
  EXPECT_NEAR(odometry.gapAround(9.1), 3.0, 1e-9);
  EXPECT_TRUE(odometry.hasSampleBefore(6.15));
  EXPECT_FALSE(odometry.hasSampleAfter(6.15));
  EXPECT_FALSE(odometry.hasSampleBefore(-0.1));
  // A sample arriving late goes in its place (here 3.1 s late, with jump_back_s raised to 5 s).
  OdometryTimeline tolerant(120.0, 5.0);
  for (double t : {0.0, 0.1, 1.0, 6.0, 6.1}) tolerant.add(t);
  tolerant.add(3.0);
  EXPECT_NEAR(tolerant.gapAround(2.0), 2.0, 1e-9);
  odometry.add(3.0);  // with the default 1 s, that is time jumping back: start over
  EXPECT_EQ(odometry.size(), 1u);
}

TEST(OdometryTimeline, ForgetsSamplesBeyondItsHorizon) {
  OdometryTimeline odometry(10.0);
  for (int i = 0; i <= 1000; ++i) odometry.add(0.1 * i);
  EXPECT_LE(odometry.size(), 102u);
  EXPECT_TRUE(std::isinf(odometry.gapAround(50.0)));
  EXPECT_NEAR(odometry.gapAround(95.05), 0.1, 1e-9);
  // A jump back in time (a looping bag) starts over; a sample a little late goes in its place.
  odometry.add(99.5);
  EXPECT_GT(odometry.size(), 2u);
  odometry.add(1.0);
  EXPECT_EQ(odometry.size(), 1u);
}

TEST(FrameGate, DropsFramesOutOfOrderStaleOrInAnOdometryGap) {
  IngestionConfig config;
  config.max_frame_age_s = 2.0;
  config.max_odometry_gap_s = 0.5;
  FrameGate gate(config);
  EXPECT_EQ(gate.admit(10.0, 10.0), FrameDrop::kNone);
  EXPECT_EQ(gate.admit(10.1, 10.2), FrameDrop::kNone);
  EXPECT_EQ(gate.admit(10.05, 10.2), FrameDrop::kOutOfOrder);  // arrived late
  EXPECT_EQ(gate.admit(10.1, 10.2), FrameDrop::kOutOfOrder);   // the same frame again
  EXPECT_EQ(gate.admit(10.2, 13.0), FrameDrop::kStale);
  EXPECT_EQ(gate.admit(12.5, 13.0), FrameDrop::kNone);
  gate.reset();  // a time jump: earlier stamps are fine again
  EXPECT_EQ(gate.admit(1.0, 1.0), FrameDrop::kNone);

  OdometryTimeline odometry;
  EXPECT_EQ(gate.checkOdometry(1.0, odometry), FrameDrop::kNone);  // no timeline: not judged
  odometry.add(1.5);
  EXPECT_EQ(gate.checkOdometry(1.0, odometry), FrameDrop::kNone);  // none before: not judged
  odometry.clear();
  odometry.add(0.0);
  odometry.add(0.2);
  odometry.add(5.2);
  EXPECT_EQ(gate.checkOdometry(0.1, odometry), FrameDrop::kNone);
  EXPECT_EQ(gate.checkOdometry(2.0, odometry), FrameDrop::kOdometryGap);
}

TEST(FrameDropCounts, SaysWhatWasDroppedAndWhy) {
  FrameDropCounts drops;
  EXPECT_EQ(drops.summary(), "none dropped");
  drops.add(FrameDrop::kOutOfOrder, 2);
  drops.add(FrameDrop::kOdometryGap);
  EXPECT_EQ(drops.total(), 3u);
  EXPECT_EQ(drops.summary(), "3 dropped (2 out of order, 1 odometry gap)");
  EXPECT_EQ(unsynchronisedFrames({10, 12, 11, 3}, 9), 3u);
  EXPECT_EQ(unsynchronisedFrames({}, 0), 0u);
}

}  // namespace
}  // namespace geofusion
