// The stage clock (host/stage_times): nested stages are charged their own time only, stages keep
// the order they first ran in, and a StageScope does nothing on a device that is not profiled.
#include "host/stage_times.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "host/device.hpp"

namespace talus {
namespace {

void sleep_ms(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

double total_of(const StageTimes& t, const std::string& name) {
  for (const auto& [n, s] : t.totals())
    if (n == name) return s;
  return -1.0;
}

// an outer stage of 60 ms holding an inner one of 40 ms: outer 20 ms, inner 40 ms (sleeps last at
// least as long as asked; a loaded machine may add a little, so the bounds are one-sided where
// they must be)
TEST(StageTimes, NestedStagesAreChargedTheirOwnTime) {
  StageTimes t;
  t.enter("outer");
  sleep_ms(10);
  t.enter("inner");
  sleep_ms(40);
  t.leave();
  sleep_ms(10);
  t.leave();
  ASSERT_EQ(t.totals().size(), 2u);
  EXPECT_EQ(t.totals()[0].first, "outer");
  EXPECT_EQ(t.totals()[1].first, "inner");
  EXPECT_GE(total_of(t, "inner"), 0.040);
  EXPECT_GE(total_of(t, "outer"), 0.020);
  // the inner stage's time is not also in the outer one
  EXPECT_LT(total_of(t, "outer"), 0.040);
}

// a stage entered again adds to its total; clear() forgets everything
TEST(StageTimes, RepeatedStagesAccumulateAndClearForgets) {
  StageTimes t;
  for (int k = 0; k < 3; ++k) {
    t.enter("sweep");
    sleep_ms(5);
    t.leave();
  }
  ASSERT_EQ(t.totals().size(), 1u);
  EXPECT_GE(total_of(t, "sweep"), 0.015);
  t.clear();
  EXPECT_TRUE(t.totals().empty());
}

// StageScope charges the device's clock while one is set, and nothing otherwise
TEST(StageTimes, ScopesChargeOnlyAProfiledDevice) {
  Device dev;
  StageTimes t;
  { StageScope off(dev, "unprofiled"); }
  dev.set_stage_times(&t);
  {
    StageScope on(dev, "profiled");
    sleep_ms(2);
  }
  dev.set_stage_times(nullptr);
  ASSERT_EQ(t.totals().size(), 1u);
  EXPECT_EQ(t.totals()[0].first, "profiled");
  EXPECT_GE(t.totals()[0].second, 0.002);
}

}  // namespace
}  // namespace talus
