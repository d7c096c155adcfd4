// The time-jump gate of the synchronised inputs (a bag that loops): the first set of the new loop
// is kept whichever input shows the jump first, the old loop's last messages still in flight are
// dropped instead of starting a second jump, and an input that never jumps is let through again.
#include "geofusion/common/time_jump.h"

#include <gtest/gtest.h>

namespace geofusion {
namespace {

// Four inputs (rgb, depth, info, detections) at 5 Hz from t = 100 s; the loop restarts at 100 s.
TEST(TimeJumpGate, TheNewLoopsFirstSetIsKeptWhicheverInputJumpsFirst) {
  TimeJumpGate gate(4, 1.0);
  double wall = 0.0;
  for (int k = 0; k < 80; ++k)
    for (std::size_t i = 0; i < 4; ++i) EXPECT_TRUE(gate.onMessage(i, 100.0 + 0.2 * k, wall).keep);
  // The loop: depth's first message comes first, then the old loop's last rgb (in flight), then
  // the new loop's first rgb, info and detections.
  const TimeJumpGate::Decision first = gate.onMessage(1, 100.0, wall += 0.01);
  EXPECT_TRUE(first.jumped);
  EXPECT_TRUE(first.keep);
  EXPECT_DOUBLE_EQ(first.from_s, 115.8);
  const TimeJumpGate::Decision straggler = gate.onMessage(0, 115.8, wall += 0.001);
  EXPECT_FALSE(straggler.keep);
  EXPECT_FALSE(straggler.jumped);
  for (std::size_t i : {0u, 2u, 3u}) {
    const TimeJumpGate::Decision d = gate.onMessage(i, 100.0, wall += 0.001);
    EXPECT_TRUE(d.keep) << "input " << i;
    EXPECT_FALSE(d.jumped) << "input " << i;
  }
  // The new loop goes on without another jump.
  for (int k = 1; k < 10; ++k) {
    for (std::size_t i = 0; i < 4; ++i) {
      const TimeJumpGate::Decision d = gate.onMessage(i, 100.0 + 0.2 * k, wall += 0.05);
      EXPECT_TRUE(d.keep && !d.jumped) << "frame " << k << " input " << i;
    }
  }
  EXPECT_EQ(gate.jumps(), 1);
}

TEST(TimeJumpGate, SmallStampDisorderIsNoJumpAndASilentInputIsLetThroughAgain) {
  TimeJumpGate gate(2, 1.0, 2.0);
  EXPECT_TRUE(gate.onMessage(0, 50.0, 0.0).keep);
  EXPECT_TRUE(gate.onMessage(1, 50.0, 0.0).keep);
  const TimeJumpGate::Decision late = gate.onMessage(0, 49.5, 0.1);  // within the tolerance
  EXPECT_TRUE(late.keep);
  EXPECT_FALSE(late.jumped);
  // A restarted driver on input 0 only (back to 10 s); input 1 keeps its clock: its messages are
  // held back as from before the jump until the join timeout, then let through.
  EXPECT_TRUE(gate.onMessage(0, 10.0, 1.0).jumped);
  EXPECT_FALSE(gate.onMessage(1, 50.2, 1.5).keep);
  EXPECT_TRUE(gate.onMessage(1, 50.4, 3.5).keep);
  EXPECT_TRUE(gate.onMessage(1, 50.6, 3.6).keep);
  EXPECT_EQ(gate.jumps(), 1);
  // An input index the gate does not know, and a message without a stamp, are passed on.
  EXPECT_TRUE(gate.onMessage(7, 1.0, 4.0).keep);
  const TimeJumpGate::Decision unstamped = gate.onMessage(1, 0.0, 4.0);
  EXPECT_TRUE(unstamped.keep);
  EXPECT_FALSE(unstamped.jumped);
  EXPECT_EQ(gate.jumps(), 1);
}

// A slow input whose last message from before the jump comes after the join timeout: let
// through, and its next message (the new loop's) starts no second epoch.
TEST(TimeJumpGate, ALateMessageFromBeforeTheJumpStartsNoSecondJump) {
  TimeJumpGate gate(3, 1.0, 2.0);
  for (std::size_t i = 0; i < 3; ++i) gate.onMessage(i, 30.0, 0.0);
  EXPECT_TRUE(gate.onMessage(0, 10.0, 1.0).jumped);
  EXPECT_TRUE(gate.onMessage(1, 10.0, 1.0).keep);
  EXPECT_TRUE(gate.onMessage(2, 30.2, 3.5).keep);  // late, after the timeout
  const TimeJumpGate::Decision next = gate.onMessage(2, 10.2, 3.6);
  EXPECT_TRUE(next.keep);
  EXPECT_FALSE(next.jumped);
  EXPECT_TRUE(gate.onMessage(0, 10.2, 3.6).keep);
  EXPECT_FALSE(gate.onMessage(2, 10.4, 3.8).jumped);
  EXPECT_EQ(gate.jumps(), 1);
}

}  // namespace
}  // namespace geofusion
