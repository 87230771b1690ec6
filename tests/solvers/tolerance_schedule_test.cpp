// Where a step's sweeps look at their residual (solvers/tolerance_schedule).
#include "solvers/tolerance_schedule.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "host/error.hpp"

namespace talus {
namespace {

// the looks a schedule makes on a residual r(n) of the sweeps, up to `cap` sweeps
std::vector<int> looks(double tolerance, const std::function<double(int)>& residual, int cap) {
  ToleranceSchedule schedule(tolerance);
  std::vector<int> at;
  while (schedule.next_look() <= cap) {
    const int n = schedule.next_look();
    at.push_back(n);
    if (schedule.look(n, residual(n))) break;
  }
  return at;
}

// a residual falling as 1/n (what HD27-D200's steps show, docs/dem.md): the first two looks ten
// sweeps apart, then the power law through them puts the look where 1/n meets the tolerance,
// capped at kMaxLookStride sweeps on; the residual exactly at the tolerance is not below it
TEST(ToleranceSchedule, APowerLawResidualIsMetAtTheSweepItCrossesTheTolerance) {
  const auto at = looks(
      1.0e-4, [](int n) { return 1.0e-2 / n; }, 1000);
  const std::vector<int> want{10, 20, 20 + kMaxLookStride, 100, 101};
  EXPECT_EQ(at, want);
}

// a residual that flattens (a power of the sweeps that halves after 30): each look's power law
// puts the crossing far ahead, so the looks go on, at most kMaxLookStride sweeps apart, to the cap
TEST(ToleranceSchedule, ASlowingResidualIsLookedAtUntilItIsBelow) {
  // r = 1e-2 / n^0.5 up to 30 sweeps, then half as steep: below 1e-4 only after n ~ 2.2e4
  auto residual = [](int n) {
    return n <= 30 ? 1.0e-2 / std::sqrt(n) : 1.0e-2 / std::sqrt(30.0) * std::pow(30.0 / n, 0.25);
  };
  const std::vector<int> at = looks(1.0e-4, residual, 500);
  std::printf("[ measured ] looks:");
  for (int n : at) std::printf(" %d", n);
  std::printf("\n");
  ASSERT_GE(at.size(), 3u);
  // never below the tolerance within 500 sweeps: the looks go on to the cap, each at most
  // kMaxLookStride on from the last
  for (size_t k = 1; k < at.size(); ++k) {
    EXPECT_GT(at[k], at[k - 1]);
    EXPECT_LE(at[k] - at[k - 1], kMaxLookStride);
  }
  EXPECT_GT(at.back(), 500 - kMaxLookStride);
}

// a residual that rises between two looks gives no power law: the next look ten sweeps on
TEST(ToleranceSchedule, ARisingResidualIsLookedAtAgainTenSweepsOn) {
  ToleranceSchedule schedule(1.0e-4);
  EXPECT_EQ(schedule.next_look(), kFirstLookInterval);
  EXPECT_FALSE(schedule.look(10, 1.0e-3));
  EXPECT_EQ(schedule.next_look(), 20);
  EXPECT_FALSE(schedule.look(20, 2.0e-3));
  EXPECT_EQ(schedule.next_look(), 30);
  // below the tolerance: the sweeps end
  EXPECT_TRUE(schedule.look(30, 0.5e-4));
}

TEST(ToleranceSchedule, AToleranceThatIsNotPositiveIsRefused) {
  EXPECT_THROW(ToleranceSchedule(0.0), InputError);
  EXPECT_THROW(ToleranceSchedule(-1.0e-4), InputError);
  EXPECT_THROW(ToleranceSchedule(std::nan("")), InputError);
}

}  // namespace
}  // namespace talus
