// Residuals against the data's own noise: the noise estimate, the excess of a perfect and of a
// wrong model, the phases, and what a residual moves with. Fresh random noise each run.
#include "sim2real/residuals.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "host/error.hpp"
#include "synthetic_runs.hpp"

namespace talus::sim2real {
namespace {

std::mt19937_64 fresh_rng() { return std::mt19937_64(std::random_device{}()); }

// a measured run: the reference series with white noise of `sigma` on every channel but t
sim2real::Run noisy_reference(double sigma_fraction, std::mt19937_64& rng) {
  sim2real::Run r;
  r.series = test::reference_series();
  for (size_t c = 1; c < kChannelCount; ++c) {
    double scale = 0.0;
    for (double v : r.series.columns[c]) scale = std::max(scale, std::abs(v));
    std::normal_distribution<double> noise(0.0, sigma_fraction * std::max(scale, 1.0));
    for (double& v : r.series.columns[c]) v += noise(rng);
  }
  r.summary.dig_start_s = test::kDigStart;
  r.summary.dig_end_s = test::kDigEnd;
  return r;
}

TEST(Residuals, NoiseSigmaOfWhiteNoiseOnASmoothSignal) {
  auto rng = fresh_rng();
  std::normal_distribution<double> noise(0.0, 0.3);
  std::vector<double> x;
  for (int i = 0; i < 2000; ++i) x.push_back(100.0 * std::sin(0.01 * i) + noise(rng));
  // 2000 samples: the MAD estimate scatters by about 3 %
  EXPECT_NEAR(noise_sigma(x), 0.3, 0.03);
  // a step (a command) barely moves it: the median ignores the two samples at the corner
  for (int i = 1000; i < 2000; ++i) x[i] += 50.0;
  EXPECT_NEAR(noise_sigma(x), 0.3, 0.03);
  // noise-free data gets the floor, not zero
  std::vector<double> clean(100, 5.0);
  EXPECT_GT(noise_sigma(clean), 0.0);
  EXPECT_LE(noise_sigma(clean), 1e-5 * 5.0);
}

TEST(Residuals, APerfectModelLeavesNoExcessAndABiasDoes) {
  auto rng = fresh_rng();
  const sim2real::Run measured = noisy_reference(0.01, rng);
  sim2real::Run model;
  model.series = test::reference_series();
  const auto sigma = noise_sigmas(measured.series);
  const Residuals perfect = compute_residuals(model, measured, sigma);
  ASSERT_EQ(perfect.phases.size(), 3u);  // approach, dig, after
  EXPECT_EQ(perfect.cells.size(), 13u * 3u);
  // the noise alone may lift a cell a little over the allowance (MSE of a few dozen samples
  // scatters: 1.62 sigma^2 in one of 39 cells was seen in CI, excess 0.08), never far
  EXPECT_LT(perfect.excess, 0.5);
  // the log-ratio is near 0 per cell: MSE ≈ σ²
  EXPECT_NEAR(perfect.log_ratio / perfect.cells.size(), 0.0, 0.25);

  // a bias of 3 σ on f_lift in the model: MSE = 10 σ², excess ln(10 / 1.5) ≈ 1.9 per phase
  sim2real::Run biased = model;
  for (double& v : biased.series[Channel::f_lift]) v += 3.0 * sigma[1];
  const Residuals wrong = compute_residuals(biased, measured, sigma);
  const double expected = std::log(10.0 / kNoiseAllowance);
  EXPECT_NEAR(wrong.excess_of({1}), 3.0 * expected, 3.0 * 0.15);
  // the other channels keep exactly what the noise gave the perfect model
  EXPECT_NEAR(wrong.excess - wrong.excess_of({1}), perfect.excess - perfect.excess_of({1}), 1e-12);
  EXPECT_EQ(wrong.excess_of({2, 3}), perfect.excess_of({2, 3}));
  for (const auto& cell : wrong.cells) {
    if (cell.channel == 1) {
      EXPECT_NEAR(cell.mean, -3.0 * sigma[1], 0.5 * sigma[1]);
    }
  }
}

TEST(Residuals, PhasesFollowTheDigMarks) {
  sim2real::Run r;
  r.series = test::reference_series();
  r.summary.dig_start_s = 2.0;
  r.summary.dig_end_s = 8.0;
  const auto phases = run_phases(r);
  ASSERT_EQ(phases.size(), 3u);
  EXPECT_EQ(phases[0].name, "approach");
  EXPECT_EQ(phases[1].name, "dig");
  EXPECT_EQ(phases[2].name, "after");
  EXPECT_DOUBLE_EQ(phases[1].t0, 2.0);
  EXPECT_DOUBLE_EQ(phases[1].t1, 8.0);
  r.summary.dig_start_s.reset();
  ASSERT_EQ(run_phases(r).size(), 1u);
  EXPECT_EQ(run_phases(r)[0].name, "run");
}

TEST(Residuals, ASimulationShorterThanTheMeasurementIsAnInputError) {
  sim2real::Run measured;
  measured.series = test::reference_series();
  sim2real::Run model;
  model.series = select_window(test::reference_series(), 0.0, 5.0);
  EXPECT_THROW(compute_residuals(model, measured, noise_sigmas(measured.series)), InputError);
}

TEST(Residuals, AResidualProportionalToTheLiftRateMovesWithIt) {
  auto rng = fresh_rng();
  sim2real::Run measured;
  measured.series = test::reference_series();
  // a lift stroke that speeds up and slows down
  auto& d = measured.series[Channel::d_lift];
  const auto& t = measured.series[Channel::t];
  for (size_t i = 0; i < t.size(); ++i) d[i] = 0.5 + 0.1 * std::sin(t[i]);
  std::normal_distribution<double> noise(0.0, 1e-3);
  std::vector<double> residual(t.size());
  for (size_t i = 0; i < t.size(); ++i) residual[i] = 0.1 * std::cos(t[i]) + noise(rng);
  const Correlate c = strongest_correlate(residual, measured);
  EXPECT_EQ(c.quantity, "lift_rate");
  EXPECT_GT(c.r, 0.95);
}

}  // namespace
}  // namespace talus::sim2real
