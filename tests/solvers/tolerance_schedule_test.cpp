// Where a step's sweeps look at their residual (solvers/tolerance_schedule).
#include "solvers/tolerance_schedule.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
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
// sweeps apart, then the power law through them puts the look past where 1/n meets the
// tolerance (100), capped at kMaxLookStride = 40 sweeps on; the residual exactly at the
// tolerance is not below it
TEST(ToleranceSchedule, APowerLawResidualIsMetAtTheSweepItCrossesTheTolerance) {
  static_assert(kMaxLookStride == 40, "the looks below are written for a stride of 40");
  auto residual = [](int n) { return 1.0e-2 / n; };
  const std::vector<int> want{10, 20, 60, 100, 101};
  EXPECT_EQ(looks(1.0e-4, residual, 1000), want);
}

// a residual falling as 1/n^2: the power law through the looks at 10 and 20 (1e-4, 2.5e-5) has
// p = 2 and meets 1e-5 at 20 sqrt(2.5) = 31.6, so the third look is the first sweep past it, 32
// (9.8e-6: below). Taking 1/p for p would put it at 60
TEST(ToleranceSchedule, ThePowerOfTheLastTwoLooksPlacesTheNext) {
  auto residual = [](int n) { return 1.0e-2 / (static_cast<double>(n) * n); };
  const std::vector<int> want{10, 20, 32};
  EXPECT_EQ(looks(1.0e-5, residual, 1000), want);
}

// a residual that flattens (a power of the sweeps that halves after 30): each look's power law
// puts the crossing far ahead, so the looks go on, at most kMaxLookStride sweeps apart, to the cap
TEST(ToleranceSchedule, AFlatteningResidualIsLookedAtUpToTheCap) {
  // r = 1e-2 / n^0.5 up to 30 sweeps, then half as steep: below 1e-4 only after n ~ 3e6
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

// a residual that is not a number or infinite (a state gone bad) is never below the tolerance
// and gives no power law: the looks go on ten sweeps apart
TEST(ToleranceSchedule, AResidualThatIsNotFiniteNeitherStopsNorPlacesTheLooks) {
  ToleranceSchedule schedule(1.0e-4);
  EXPECT_FALSE(schedule.look(10, std::nan("")));
  EXPECT_EQ(schedule.next_look(), 20);
  EXPECT_FALSE(schedule.look(20, 1.0e-3));
  EXPECT_EQ(schedule.next_look(), 30);
  EXPECT_FALSE(schedule.look(30, std::numeric_limits<double>::infinity()));
  EXPECT_EQ(schedule.next_look(), 40);
  EXPECT_FALSE(schedule.look(40, 1.0e-3));
  EXPECT_EQ(schedule.next_look(), 50);
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
