#include "geofusion/common/input_monitor.h"
#include "test_data.h"

#include <gtest/gtest.h>

namespace geofusion {
namespace {

bool mentions(const std::vector<std::string>& problems, const std::string& what) {
  return test::anyMentions(problems, what);
}

InputMonitor::Config config() {
  InputMonitor::Config c;
  c.stale_after_s = 2.0;
  c.sync_timeout_s = 3.0;
  return c;
}

TEST(InputMonitor, QuietWhileEverythingArrivesAndSynchronises) {
  InputMonitor m({"/rgb", "/depth"}, config(), 0.0);
  for (int i = 1; i < 100; ++i) {
    const double t = 0.1 * i;
    m.onMessage(0, t);
    m.onMessage(1, t);
    m.onSynchronized(t);
    EXPECT_TRUE(m.problems(t).empty()) << m.problems(t).front();
  }
  EXPECT_EQ(m.synchronizedCount(), 99u);
}

TEST(InputMonitor, NamesAnInputThatNeverArrives) {
  InputMonitor m({"/rgb", "/detections"}, config(), 0.0);
  for (double t = 0.1; t < 1.5; t += 0.1) m.onMessage(0, t);
  EXPECT_TRUE(m.problems(1.5).empty());  // still within the grace period
  m.onMessage(0, 2.5);
  const auto p = m.problems(2.5);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_TRUE(mentions(p, "no message received on /detections")) << p[0];
}

TEST(InputMonitor, NamesAnInputThatStopped) {
  InputMonitor m({"/rgb", "/depth"}, config(), 0.0);
  for (double t = 0.1; t < 5.0; t += 0.1) {
    m.onMessage(0, t);
    if (t < 2.0) m.onMessage(1, t);
    m.onSynchronized(t);
  }
  const auto p = m.problems(5.0);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_TRUE(mentions(p, "input /depth stopped")) << p[0];
  EXPECT_FALSE(mentions(p, "/rgb"));
}

TEST(InputMonitor, SaysWhenInputsArriveButNeverSynchronise) {
  InputMonitor m({"/rgb", "/detections"}, config(), 0.0);
  for (double t = 0.1; t < 2.0; t += 0.1) {
    m.onMessage(0, t);
    m.onMessage(1, t);
  }
  EXPECT_TRUE(m.problems(2.0).empty());
  for (double t = 2.0; t < 4.0; t += 0.1) {
    m.onMessage(0, t);
    m.onMessage(1, t);
  }
  const auto p = m.problems(4.0);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_TRUE(mentions(p, "never synchronise")) << p[0];
  EXPECT_TRUE(mentions(p, "/detections")) << p[0];
  // Once they synchronise, the complaint goes away.
  m.onSynchronized(4.0);
  EXPECT_TRUE(m.problems(4.1).empty());
  // ... and comes back, worded differently, if synchronisation stops.
  for (double t = 4.1; t < 8.0; t += 0.1) {
    m.onMessage(0, t);
    m.onMessage(1, t);
  }
  EXPECT_TRUE(mentions(m.problems(8.0), "stopped synchronising"));
}

TEST(InputMonitor, ResetForgetsHistory) {
  InputMonitor m({"/rgb"}, config(), 0.0);
  m.onMessage(0, 0.5);
  EXPECT_FALSE(m.problems(10.0).empty());
  m.reset(10.0);
  EXPECT_EQ(m.messageCount(0), 0u);
  EXPECT_TRUE(m.problems(11.0).empty());
}

}  // namespace
}  // namespace geofusion
