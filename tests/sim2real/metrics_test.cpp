// Hand-checkable cases for the error measures of sim2real/metrics.hpp.
#include "sim2real/metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "host/error.hpp"

namespace talus::sim2real {
namespace {

// rounding tolerance for sums of a handful of O(1) doubles
constexpr double kTight = 1e-14;

Trajectory rows(std::initializer_list<std::initializer_list<double>> points) {
  Trajectory x(static_cast<Eigen::Index>(points.size()),
               static_cast<Eigen::Index>(points.begin()->size()));
  Eigen::Index i = 0;
  for (const auto& p : points) {
    Eigen::Index j = 0;
    for (double v : p) x(i, j++) = v;
    ++i;
  }
  return x;
}

TEST(MetricsTest, MaeByHand) {
  // |1-2| + |2-2| + |3-5| + |-4-(-4)| = 3 over N = 4 samples, f_norm = max|f̂| = 5
  const std::vector<double> f = {1, 2, 3, -4};
  const std::vector<double> ref = {2, 2, 5, -4};
  EXPECT_NEAR(normalised_mae(f, ref), 3.0 / (4.0 * 5.0), kTight);
  // an explicit f_norm replaces max|f̂|
  EXPECT_NEAR(normalised_mae(f, ref, 2.0), 3.0 / (4.0 * 2.0), kTight);
  EXPECT_DOUBLE_EQ(max_abs({-7.0, 3.0}), 7.0);
}

TEST(MetricsTest, MaeIsScaleInvariantSoTheForceConstantCancels) {
  // dividing both series by a force constant c leaves E_f with f_norm = max|f̂| unchanged
  const std::vector<double> f = {1.0e5, 1.3e5, 0.7e5};
  const std::vector<double> ref = {1.1e5, 1.2e5, 0.9e5};
  const double c = 148.8e3;
  std::vector<double> fs, rs;
  for (double v : f) fs.push_back(v / c);
  for (double v : ref) rs.push_back(v / c);
  EXPECT_NEAR(normalised_mae(fs, rs), normalised_mae(f, ref), kTight);
}

TEST(MetricsTest, MaeRejectsBadInput) {
  EXPECT_THROW(normalised_mae({1.0}, {1.0, 2.0}), Error);
  EXPECT_THROW(normalised_mae({}, {}), Error);
  // an all-zero reference cannot normalise
  EXPECT_THROW(normalised_mae({1.0, 2.0}, {0.0, 0.0}), InputError);
}

TEST(MetricsTest, MeeByHand) {
  // errors (3,4) -> 5 and (0,0) -> 0: mean 2.5, L_norm 10
  const Trajectory x = rows({{3, 4}, {1, 1}});
  const Trajectory ref = rows({{0, 0}, {1, 1}});
  EXPECT_NEAR(normalised_mee(x, ref, 10.0), 2.5 / 10.0, kTight);
  EXPECT_THROW(normalised_mee(x, ref, 0.0), InputError);
}

TEST(MetricsTest, TrajectoryExtentIsBoundingBoxDiagonal) {
  // x spans 3 m, z spans 4 m -> 5 m; independent of where the origin is
  const Trajectory a = rows({{0, 0}, {3, 1}, {1, 4}});
  Trajectory b = a;
  b.col(0).array() += 100.0;
  EXPECT_NEAR(trajectory_extent(a), 5.0, kTight);
  EXPECT_NEAR(trajectory_extent(b), 5.0, kTight);
}

TEST(MetricsTest, RelativeErrorAndPaperMean) {
  EXPECT_NEAR(relative_error(2.77, 3.46), (2.77 - 3.46) / 3.46, kTight);
  EXPECT_THROW(relative_error(1.0, 0.0), InputError);
  // mean of absolute values: signs of E_M and E_W do not cancel
  ErrorColumns e{0.1, 0.2, 0.3, 0.4, 0.5, -0.6, -0.7};
  EXPECT_NEAR(paper_mean(e), 2.8 / 7.0, kTight);
}

TEST(MetricsTest, AnEmptyMeasuredBucketLeavesTheMassErrorUndefinedNotTheTable) {
  EXPECT_NEAR(loaded_mass_error(900.0, 1000.0), -0.1, kTight);
  EXPECT_EQ(loaded_mass_error(0.0, 0.0), 0.0);             // both empty: they agree
  EXPECT_TRUE(std::isnan(loaded_mass_error(250.0, 0.0)));  // undefined, not an abort
  EXPECT_THROW(loaded_mass_error(-1.0, 100.0), InputError);
  EXPECT_THROW(loaded_mass_error(100.0, std::nan("")), InputError);
  // the row's mean skips the undefined column: six columns left
  ErrorColumns e{0.1, 0.2, 0.3, 0.4, 0.5, std::nan(""), -0.7};
  EXPECT_NEAR(paper_mean(e), 2.2 / 6.0, kTight);
  const double nan = std::nan("");
  EXPECT_TRUE(std::isnan(paper_mean(std::array<double, 7>{nan, nan, nan, nan, nan, nan, nan})));
}

TEST(DtwTest, HandComputedCumulativeMatrix) {
  // 1-D: a = [0,1,2], b = [0,2]; c = [[0,2],[1,1],[2,0]];
  // d = [[0,2],[1,1],[3,1]] -> distance 1
  const Trajectory a = rows({{0}, {1}, {2}});
  const Trajectory b = rows({{0}, {2}});
  EXPECT_NEAR(dtw_distance(a, b), 1.0, kTight);
  // symmetric in its arguments (the recurrence is symmetric under transposition)
  EXPECT_NEAR(dtw_distance(b, a), 1.0, kTight);
}

TEST(DtwTest, SinglePointAgainstCurveSumsAllDistances) {
  // one point against M points: the only warping path visits every cell: Σ_j ‖a_0 − b_j‖
  const Trajectory a = rows({{0, 0}});
  const Trajectory b = rows({{3, 4}, {0, 1}, {6, 8}});
  EXPECT_NEAR(dtw_distance(a, b), 5.0 + 1.0 + 10.0, kTight);
}

TEST(DtwTest, TimeWarpCostsNothingButMeeSeesIt) {
  // the same path traced with a delay: DTW 0, while the momentaneous error is not
  const Trajectory ref = rows({{0, 0}, {1, 0}, {2, 0}, {3, 0}});
  const Trajectory slow = rows({{0, 0}, {0, 0}, {1, 0}, {2, 0}, {3, 0}});
  EXPECT_NEAR(dtw_distance(ref, slow), 0.0, kTight);
  const Trajectory delayed = rows({{0, 0}, {0, 0}, {1, 0}, {2, 0}});
  EXPECT_GT(normalised_mee(delayed, ref, 3.0), 0.2);
}

TEST(DtwTest, ParallelOffsetGivesOffsetPerSample) {
  // two equally sampled parallel lines 0.03 m apart: d = N · 0.03, E_DTW = 0.03 / L_norm
  const int n = 50;
  Trajectory ref(n, 2), sim(n, 2);
  for (int i = 0; i < n; ++i) {
    ref.row(i) << 0.1 * i, 0.0;
    sim.row(i) << 0.1 * i, 0.03;
  }
  const double d = dtw_distance(ref, sim);
  EXPECT_NEAR(d, n * 0.03, 1e-12);
  EXPECT_NEAR(normalised_dtw(d, n, 0.6), 0.05, 1e-12);
}

}  // namespace
}  // namespace talus::sim2real
