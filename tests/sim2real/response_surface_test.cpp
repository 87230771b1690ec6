// The local response surface of a one-parameter fit: the window around the scan's best point,
// and the least-squares parabola whose vertex is the estimate on a rough objective. Fresh random
// objectives each run (the seed printed).
#include "sim2real/response_surface.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "host/error.hpp"
#include "synthetic_runs.hpp"

namespace talus::sim2real {
namespace {

using test::fresh_rng;

// the coarse scan's cell centres of nine cells, as sim2real/diagnose scans one parameter
std::vector<double> nine_centres() {
  std::vector<double> axis;
  axis.reserve(9);
  for (int i = 0; i < 9; ++i) axis.push_back((i + 0.5) / 9.0);
  return axis;
}

TEST(FitWindow, SpansTheBestPointsNeighboursWithEvenlySpacedNewPoints) {
  const std::vector<double> axis = nine_centres();
  const FitWindow w = fit_window(axis, axis[4], 3);
  EXPECT_DOUBLE_EQ(w.lo, axis[3]);
  EXPECT_DOUBLE_EQ(w.hi, axis[5]);
  // three on each side at a quarter of the spacing, none of them a scan point
  ASSERT_EQ(w.new_points.size(), 6u);
  const double quarter = (axis[5] - axis[4]) / 4.0;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(w.new_points[k], axis[3] + (k + 1) * quarter, 1e-15);
    EXPECT_NEAR(w.new_points[3 + k], axis[4] + (k + 1) * quarter, 1e-15);
  }
  EXPECT_TRUE(std::is_sorted(w.new_points.begin(), w.new_points.end()));
}

TEST(FitWindow, NearZeroTheSpacingIsTheNarrowerSidesAndTheOptimisersStepHalfOfIt) {
  // a range from zero: three points towards zero, each a quarter of the one before (as
  // sim2real/diagnose scan_axis makes them), then the nine centres
  std::vector<double> axis;
  for (int j = 3; j >= 1; --j) axis.push_back((0.5 / 9.0) / std::pow(4.0, j));
  for (double c : nine_centres()) axis.push_back(c);
  const FitWindow w = fit_window(axis, axis[1], 3);
  EXPECT_DOUBLE_EQ(w.lo, axis[0]);
  EXPECT_DOUBLE_EQ(w.hi, axis[2]);
  EXPECT_DOUBLE_EQ(w.spacing, (axis[1] - axis[0]) / 4.0);
  ASSERT_EQ(w.new_points.size(), 6u);
  EXPECT_TRUE(std::is_sorted(w.new_points.begin(), w.new_points.end()));
  EXPECT_GT(w.new_points.front(), w.lo);
  EXPECT_LT(w.new_points.back(), w.hi);
  // the first point: the window reaches down to zero, which is sampled
  const FitWindow first = fit_window(axis, axis[0], 3);
  EXPECT_EQ(first.lo, 0.0);
  EXPECT_EQ(first.new_points.front(), 0.0);
  EXPECT_DOUBLE_EQ(first.spacing, axis[0] / 4.0);
  // an interior window of the centres: a quarter of the scan's spacing
  EXPECT_NEAR(fit_window(axis, axis[7], 3).spacing, 1.0 / 36.0, 1e-15);
}

TEST(FitWindow, AtAnEndOfTheScanTheRangesBoundIsSampled) {
  const std::vector<double> axis = nine_centres();
  const FitWindow first = fit_window(axis, axis.front(), 3);
  EXPECT_EQ(first.lo, 0.0);
  ASSERT_EQ(first.new_points.size(), 7u);
  EXPECT_EQ(first.new_points.front(), 0.0);
  const FitWindow last = fit_window(axis, axis.back(), 3);
  EXPECT_EQ(last.hi, 1.0);
  ASSERT_EQ(last.new_points.size(), 7u);
  EXPECT_EQ(last.new_points.back(), 1.0);
  // the best point must be one of the scan's
  EXPECT_THROW(fit_window(axis, 0.3, 3), Error);
}

TEST(FitParabola, FindsAnExactParabolasMinimumWithNoRoughness) {
  std::mt19937_64 rng = fresh_rng();
  std::uniform_real_distribution<double> where(0.35, 0.55), scale(0.5, 20.0);
  const double truth = where(rng), k = scale(rng);
  std::vector<double> u, y;
  for (int i = 0; i <= 8; ++i) {
    u.push_back(0.3 + 0.3 * i / 8.0);
    y.push_back(3.0 + k * (u.back() - truth) * (u.back() - truth));
  }
  const LocalParabola p = fit_parabola(u, y, 0.3, 0.6);
  ASSERT_TRUE(p.convex);
  EXPECT_NEAR(p.vertex, truth, 1e-9);
  EXPECT_NEAR(p.at_vertex, 3.0, 1e-9);
  EXPECT_LT(p.roughness(), 1e-9);
}

TEST(FitParabola, AConcaveTrendHasNoMinimumAndAVertexOutsideIsClamped) {
  const std::vector<double> u = {0.0, 0.25, 0.5, 0.75, 1.0};
  std::vector<double> y;
  y.reserve(u.size());
  for (double v : u) y.push_back(-(v - 0.5) * (v - 0.5));
  EXPECT_FALSE(fit_parabola(u, y, 0.0, 1.0).convex);
  // a minimum at 1.5, beyond the window [0, 1]: the estimate stops at the window's end
  y.clear();
  for (double v : u) y.push_back((v - 1.5) * (v - 1.5));
  const LocalParabola p = fit_parabola(u, y, 0.0, 1.0);
  ASSERT_TRUE(p.convex);
  EXPECT_DOUBLE_EQ(p.vertex, 1.0);
  EXPECT_TRUE(p.clamped);
  EXPECT_FALSE(fit_parabola(u, {0.3, 0.1, 0.0, 0.1, 0.3}, 0.0, 1.0).clamped);
  // fewer than three distinct points determine no parabola
  EXPECT_THROW(fit_parabola({0.2, 0.2, 0.4}, {1.0, 1.0, 2.0}, 0.0, 1.0), Error);
  EXPECT_THROW(fit_parabola({0.2, 0.4}, {1.0, 2.0}, 0.0, 1.0), Error);
}

TEST(LocalMinima, OneForATrendHoweverSharpSeveralForARoughOne) {
  // a smooth likelihood's shape, the log of a squared residual: sharp at the optimum, not a
  // parabola, one minimum; samples given out of order
  const std::vector<double> u = {0.5, 0.0, 0.125, 0.25, 0.375, 0.625, 0.75, 0.875, 1.0};
  std::vector<double> y;
  y.reserve(u.size());
  for (double v : u) y.push_back(std::log(1e-4 + (v - 0.41) * (v - 0.41)));
  EXPECT_EQ(local_minima(u, y), 1);
  // the same with a rough part: a dip beside the optimum is a second minimum
  y[6] -= 10.0;
  EXPECT_EQ(local_minima(u, y), 2);
  // a minimum at either end counts, a plateau once
  EXPECT_EQ(local_minima({0.0, 0.5, 1.0}, {0.0, 1.0, 2.0}), 1);
  EXPECT_EQ(local_minima({0.0, 0.5, 1.0}, {2.0, 1.0, 0.0}), 1);
  EXPECT_EQ(local_minima({0.0, 0.5, 1.0}, {0.0, 1.0, 0.0}), 2);
  EXPECT_EQ(local_minima({0.0, 0.25, 0.5, 0.75, 1.0}, {2.0, 1.0, 1.0, 1.0, 2.0}), 1);
  EXPECT_EQ(local_minima({0.0, 0.5, 1.0}, {1.0, 1.0, 1.0}), 1);
  EXPECT_THROW(local_minima({0.0, 0.5, 1.0}, {1.0, std::nan(""), 1.0}), Error);
}

// the fit's decision on the samples of a real window (the scan's three points and six new ones):
// a smooth trend is refined; the same trend with a rough part takes the vertex, near the trend's
// minimum; a rough trend still falling at the window's edge, or one without a minimum, is refined
TEST(WindowTrend, TheVertexIsTheEstimateOnlyForARoughTrendWithItsMinimumInside) {
  std::mt19937_64 rng = fresh_rng();
  const std::vector<double> axis = nine_centres();
  const FitWindow w = fit_window(axis, axis[4], 3);
  std::vector<double> u = {axis[3], axis[4], axis[5]};
  u.insert(u.end(), w.new_points.begin(), w.new_points.end());
  std::uniform_real_distribution<double> where(axis[4] - 0.03, axis[4] + 0.03);
  const double truth = where(rng);
  // the likelihood's shape, the log of a squared residual over the noise
  const auto trend = [&](double v) { return std::log(1.0 + 400.0 * (v - truth) * (v - truth)); };
  std::vector<double> smooth, rough;
  for (double v : u) smooth.push_back(trend(v));
  // a rough part of alternating sign in the order of u (a chaotic dig's), a quarter of the rise
  std::vector<double> sorted_u = u;
  std::sort(sorted_u.begin(), sorted_u.end());
  const double rise = trend(w.hi) > trend(w.lo) ? trend(w.hi) : trend(w.lo);
  for (double v : u) {
    const auto rank = std::find(sorted_u.begin(), sorted_u.end(), v) - sorted_u.begin();
    rough.push_back(trend(v) + (rank % 2 == 0 ? 0.25 : -0.25) * rise);
  }
  const WindowTrend refined = window_trend(u, smooth, w);
  EXPECT_EQ(refined.local_minima, 1);
  EXPECT_FALSE(refined.rough());
  const WindowTrend taken = window_trend(u, rough, w);
  EXPECT_GT(taken.local_minima, 1);
  ASSERT_TRUE(taken.rough());
  EXPECT_NEAR(taken.parabola.vertex, truth, 0.25 * (w.hi - w.lo)) << "truth " << truth;
  // the same rough part on a trend whose minimum lies beyond the window (0.2 above it): refined
  // from the edge
  std::vector<double> falling;
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double beyond = u[k] - (w.hi + 0.2);
    falling.push_back(rough[k] - trend(u[k]) + 30.0 * beyond * beyond);
  }
  const WindowTrend edge = window_trend(u, falling, w);
  EXPECT_GT(edge.local_minima, 1);
  EXPECT_TRUE(edge.parabola.clamped);
  EXPECT_FALSE(edge.rough());
}

// what the window is for: on a trend with a rough part as large as a quarter of its rise across
// the window (a chaotic dig's likelihood), the parabola's vertex lands nearer the trend's minimum
// than the best single sample does, and the roughness reads the rough part's size
TEST(FitParabola, OnARoughObjectiveTheVertexBeatsTheBestSample) {
  std::mt19937_64 rng = fresh_rng();
  std::uniform_real_distribution<double> where(0.4, 0.6);
  std::normal_distribution<double> rough(0.0, 1.0);
  const int draws = 200;
  std::vector<double> vertex_error, sample_error, roughness, minima;
  for (int d = 0; d < draws; ++d) {
    // the trend rises by 1 from its minimum to the farther end of [0, 1]
    const double truth = where(rng);
    const double k = 1.0 / std::pow(std::max(truth, 1.0 - truth), 2.0);
    std::vector<double> u, y;
    for (int i = 0; i <= 8; ++i) {
      u.push_back(i / 8.0);
      y.push_back(k * (u.back() - truth) * (u.back() - truth) + 0.25 * rough(rng));
    }
    const LocalParabola p = fit_parabola(u, y, 0.0, 1.0);
    const auto best = std::min_element(y.begin(), y.end()) - y.begin();
    vertex_error.push_back(p.convex ? std::abs(p.vertex - truth) : 1.0);
    sample_error.push_back(std::abs(u[static_cast<size_t>(best)] - truth));
    roughness.push_back(p.roughness());
    minima.push_back(local_minima(u, y));
  }
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  std::printf("median error: vertex %.4f, best sample %.4f; median roughness %.3f\n",
              median(vertex_error), median(sample_error), median(roughness));
  EXPECT_LT(median(vertex_error), 0.75 * median(sample_error));
  // the samples' scatter (0.25 of the rise, less the three coefficients' share) is what the
  // roughness reads: its median about 0.19 (2,000 draws in numpy), well above an exact trend's 0
  EXPECT_GT(median(roughness), 0.12);
  EXPECT_LT(median(roughness), 0.30);
  // and the samples show it as more than one local minimum in most draws (numpy: 2 or more in
  // 92 % of 2,000)
  EXPECT_GE(median(minima), 2.0);
}

}  // namespace
}  // namespace talus::sim2real
