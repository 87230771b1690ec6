// Residuals against the data's own noise: the noise estimate, the excess of a perfect and of a
// wrong model, the phases, and what a residual moves with. Fresh random noise each run.
#include "sim2real/residuals.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "host/error.hpp"
#include "synthetic_runs.hpp"

namespace talus::sim2real {
namespace {

using test::fresh_rng;

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
  x.reserve(8000);
  for (int i = 0; i < 8000; ++i) x.push_back(100.0 * std::sin(0.0025 * i) + noise(rng));
  // the MAD of second differences scatters by 3.2 % of sigma at 2000 samples (1500 draws), so a
  // 10 % band there failed about once in 300 runs (seen in CI); at 8000 samples it scatters by
  // about 1.6 % and the band is six of its deviations, while a wrong constant (the MAD's 1.4826
  // or the second difference's sqrt(6)) still lands far outside
  EXPECT_NEAR(noise_sigma(x), 0.3, 0.03);
  // a step (a command) barely moves it: the median ignores the two samples at the corner
  for (int i = 4000; i < 8000; ++i) x[i] += 50.0;
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

// the integrated autocorrelation time of processes whose τ is known: white noise 1, an AR(1)
// of ρ (1 + ρ)/(1 − ρ), white noise beside a slow AR(1) the slow part's share of it (where the
// lag-one autocorrelation of the mix would say 2.9), an offset the whole series
TEST(Residuals, TheIntegratedAutocorrelationTimeOfKnownProcesses) {
  auto rng = fresh_rng();
  std::normal_distribution<double> unit(0.0, 1.0);
  // long enough that the estimate's scatter, about τ √(4τ / n), is a few % of τ
  constexpr int kN = 200000;
  // x_{i+1} = ρ x_i + √(1 − ρ²) e: unit variance, autocorrelation ρ^k
  const auto ar1 = [&](double rho) {
    std::vector<double> x(kN);
    double v = unit(rng);
    for (double& xi : x) {
      xi = v;
      v = rho * v + std::sqrt(1.0 - rho * rho) * unit(rng);
    }
    return x;
  };
  std::vector<double> white(kN);
  for (double& v : white) v = unit(rng);
  EXPECT_NEAR(integrated_autocorrelation_time(white), 1.0, 0.2);
  EXPECT_NEAR(integrated_autocorrelation_time(ar1(0.9)), 19.0, 0.2 * 19.0);
  // half the variance white, half ρ = 0.98: τ = 1 + 2 Σ 0.5 · 0.98^k = 50
  std::vector<double> mix = ar1(0.98);
  for (int i = 0; i < kN; ++i) mix[i] = std::sqrt(0.5) * (mix[i] + white[i]);
  EXPECT_NEAR(integrated_autocorrelation_time(mix), 50.0, 0.3 * 50.0);
  // an offset is one sample's worth, per segment when segments are given
  std::vector<double> offset(1000, 2.0);
  std::vector<int> halves(1000, 0);
  for (int i = 500; i < 1000; ++i) {
    offset[i] = -2.0;
    halves[i] = 1;
  }
  EXPECT_NEAR(1000.0 / integrated_autocorrelation_time(offset, halves), 2.0, 0.01);
  EXPECT_NEAR(integrated_autocorrelation_time(std::vector<double>(1000, 3.0)), 1000.0, 1e-9);
  // by hand: ρ_1..ρ_7 of this series are (−6, 9, 5, −2, 9, −4, 4)/19, so the pair sums are
  // Γ = (13, 14, 7, 0)/19; the monotone sequence holds Γ_1 to Γ_0: τ = −1 + 2 (13 + 13 + 7)/19
  // (the plain initial positive sequence would give 49/19)
  EXPECT_NEAR(integrated_autocorrelation_time({-2, 1, -2, -1, 0, -2, 1, -2}), 47.0 / 19.0, 1e-12);
  // degenerate series count as independent samples; mismatched segment labels are an error
  EXPECT_EQ(integrated_autocorrelation_time({}), 1.0);
  EXPECT_EQ(integrated_autocorrelation_time({5.0}), 1.0);
  EXPECT_EQ(integrated_autocorrelation_time(std::vector<double>(10, 0.0)), 1.0);
  EXPECT_THROW(integrated_autocorrelation_time(white, {0, 1}), Error);
}

// a residual correlated in time carries fewer independent samples than it has: each cell counts
// n / τ, τ the integrated autocorrelation time of r/√w over it; white noise keeps nearly all of
// them, an AR(1) residual fewer, an offset over the whole cell about one
TEST(Residuals, ACorrelatedResidualCountsFewerEffectiveSamples) {
  auto rng = fresh_rng();
  const sim2real::Run measured = noisy_reference(0.01, rng);
  const auto sigma = noise_sigmas(measured.series);
  sim2real::Run model;
  model.series = test::reference_series();
  // white: the noise the measured run carries
  const Residuals white = compute_residuals(model, measured, sigma);
  // f_lift's model also off by an AR(1) process of ρ = 0.9 and 3 σ, f_tilt by a 5 σ offset
  sim2real::Run off = model;
  std::normal_distribution<double> unit(0.0, 1.0);
  constexpr double kRho = 0.9;
  double ar = 3.0 * sigma[1] * unit(rng);
  for (double& v : off.series[Channel::f_lift]) {
    v += ar;
    ar = kRho * ar + std::sqrt(1.0 - kRho * kRho) * 3.0 * sigma[1] * unit(rng);
  }
  for (double& v : off.series[Channel::f_tilt]) v += 5.0 * sigma[2];
  const Residuals correlated = compute_residuals(off, measured, sigma);
  // the law written out for f_lift's cells (no spread: w = 1, z = r)
  const auto r = residual_series(off, measured, 1);
  const auto& t = measured.series[Channel::t];
  double ratio_sum = 0.0;
  for (std::size_t k = 0; k < white.cells.size(); ++k) {
    const ResidualCell& w = white.cells[k];
    const ResidualCell& c = correlated.cells[k];
    SCOPED_TRACE(std::string(kChannelNames[c.channel]) + " phase " + std::to_string(c.phase) +
                 ", " + std::to_string(c.samples) + " samples");
    ASSERT_GE(w.samples, 200);
    // white noise: τ near 1, though in 200 samples the lags' chance correlations (±0.07 each)
    // can sum to more: the least of 36,000 such cells counted 0.21 n
    EXPECT_GE(w.effective_samples, 0.15 * w.samples);
    EXPECT_LE(w.effective_samples, w.samples);
    if (c.channel == 1) {
      // the AR(1) (variance 9 σ²) beside white noise (σ²): τ = 1 + 0.9 · 2 · 0.9/0.1 = 17.2 on
      // average; in a cell of 200 samples (about 20 correlation times) the estimate scatters
      EXPECT_LT(c.effective_samples, 0.4 * c.samples);
      const Phase& ph = correlated.phases[c.phase];
      const bool last = c.phase + 1 == correlated.phases.size();
      std::vector<double> z;
      for (std::size_t i = 0; i < t.size(); ++i)
        if (!(t[i] < ph.t0 || t[i] > ph.t1 || (!last && t[i] >= ph.t1))) z.push_back(r[i]);
      EXPECT_EQ(c.effective_samples, c.samples / integrated_autocorrelation_time(z));
    } else if (c.channel == 2) {
      // an offset of 5 σ over white noise: the whole cell is about one sample
      EXPECT_LT(c.effective_samples, 2.0);
      EXPECT_GE(c.effective_samples, 1.0);
    } else {
      EXPECT_EQ(c.effective_samples, w.effective_samples);
    }
    // the run's log-ratio is the cells' terms weighted by their share of the channel's samples
    ratio_sum += double(c.samples) / double(measured.series.size()) * c.log_ratio;
  }
  EXPECT_NEAR(correlated.log_ratio, ratio_sum, 1e-12 * std::max(1.0, std::abs(ratio_sum)));
}

// the law before issue 17's spread, written out here as the reference: per cell MSE against σ²
struct SensorOnly {
  std::vector<double> excess;  // per cell, in compute_residuals' order
  double total = 0.0, log_ratio = 0.0;
};
SensorOnly sensor_only_law(const sim2real::Run& simulated, const sim2real::Run& measured,
                           const std::vector<double>& sigma) {
  SensorOnly out;
  const auto phases = run_phases(measured);
  const auto& tm = measured.series[Channel::t];
  for (size_t c = 1; c < kChannelCount; ++c) {
    const auto r = residual_series(simulated, measured, c);
    for (size_t p = 0; p < phases.size(); ++p) {
      const bool last = p + 1 == phases.size();
      double sum2 = 0.0;
      int n = 0;
      for (size_t i = 0; i < tm.size(); ++i) {
        if (tm[i] < phases[p].t0 || tm[i] > phases[p].t1 || (!last && tm[i] >= phases[p].t1))
          continue;
        sum2 += r[i] * r[i];
        ++n;
      }
      if (n == 0) continue;
      const double mse = sum2 / n;
      out.excess.push_back(std::log(std::max(mse / (kNoiseAllowance * sigma[c] * sigma[c]), 1.0)));
      out.total += out.excess.back();
      out.log_ratio +=
          double(n) / double(tm.size()) * std::log(std::max(mse / (sigma[c] * sigma[c]), 1e-6));
    }
  }
  return out;
}

// a spread of the run's shape holding `v` in every channel, from an ensemble of `members`
RunSpread uniform_spread(const sim2real::Run& run, int members, double v) {
  RunSpread spread;
  spread.members = members;
  spread.variance[Channel::t] = run.series[Channel::t];
  for (size_t c = 1; c < kChannelCount; ++c)
    spread.variance.columns[c].assign(run.series.size(), v);
  return spread;
}

// a judgement with a pile ensemble's spread: the clean reference as the model (the mean of
// `members` piles, a zero spread to be filled), the measured run with sensor noise of 1 % of each
// channel's scale, and that noise's σ
struct SpreadCase {
  sim2real::Run model, measured;
  std::vector<double> sigma;
};
SpreadCase spread_case(std::mt19937_64& rng, int members) {
  SpreadCase k;
  k.model.series = test::reference_series();
  k.measured = noisy_reference(0.01, rng);
  k.sigma = noise_sigmas(k.measured.series);
  k.model.spread = uniform_spread(k.model, members, 0.0);
  return k;
}

// without a spread, and with one that is zero everywhere, the residuals are the sensor-noise law's
// bit for bit: w = 1 exactly, r² / 1 = r² and ln 1 = 0 (issue 17: the spread must not move a
// diagnosis of runs without an ensemble)
TEST(Residuals, AZeroSpreadLeavesTheSensorNoiseLawBitForBit) {
  auto rng = fresh_rng();
  const sim2real::Run measured = noisy_reference(0.01, rng);
  const auto sigma = noise_sigmas(measured.series);
  sim2real::Run model;
  model.series = test::simulated_series();  // off by several σ in several channels and phases
  const SensorOnly reference = sensor_only_law(model, measured, sigma);
  const Residuals none = compute_residuals(model, measured, sigma);
  ASSERT_EQ(none.cells.size(), reference.excess.size());
  EXPECT_GT(reference.total, 1.0);  // the case is not trivial: cells beyond noise
  for (size_t k = 0; k < none.cells.size(); ++k)
    EXPECT_EQ(none.cells[k].excess, reference.excess[k]) << k;
  EXPECT_EQ(none.excess, reference.total);
  EXPECT_EQ(none.log_ratio, reference.log_ratio);
  EXPECT_EQ(none.spread_members, 0);

  sim2real::Run zero = model;
  zero.spread = uniform_spread(model, 3, 0.0);
  const Residuals with_zero = compute_residuals(zero, measured, sigma);
  ASSERT_EQ(with_zero.cells.size(), none.cells.size());
  for (size_t k = 0; k < none.cells.size(); ++k) {
    EXPECT_EQ(with_zero.cells[k].excess, none.cells[k].excess) << k;
    EXPECT_EQ(with_zero.cells[k].rms, none.cells[k].rms) << k;
    EXPECT_EQ(with_zero.cells[k].mean, none.cells[k].mean) << k;
    EXPECT_EQ(with_zero.cells[k].spread, 0.0);
    EXPECT_EQ(with_zero.cells[k].spread_share, 0.0);
  }
  EXPECT_EQ(with_zero.excess, none.excess);
  EXPECT_EQ(with_zero.log_ratio, none.log_ratio);
  EXPECT_EQ(with_zero.spread_members, 3);
}

// the law by hand on one channel: σ = 1, f_lift's residual ±2 everywhere, its spread v = 3 over the
// first half and v = 0.75 over the second, N = 3, so (1 + 1/N) v = 4 and 1 and w = 5 and 2. The
// other channels have no residual and no spread, so only f_lift's terms differ between the two
TEST(Residuals, EachSampleIsJudgedAgainstSigmaSquaredPlusOnePlusOneOverNTimesV) {
  sim2real::Run measured;
  measured.series = test::reference_series();  // 1001 samples, no marks: one phase
  sim2real::Run model = measured;
  const size_t n = measured.series.size();
  for (size_t i = 0; i < n; ++i) measured.series[Channel::f_lift][i] += i % 2 == 0 ? 2.0 : -2.0;
  const std::vector<double> sigma(kChannelCount, 1.0);
  const Residuals none = compute_residuals(model, measured, sigma);
  model.spread = uniform_spread(model, 3, 0.0);
  const size_t half = n / 2;  // samples [0, half) at v = 3, [half, n) at v = 0.75
  for (size_t i = 0; i < n; ++i) model.spread->variance[Channel::f_lift][i] = i < half ? 3.0 : 0.75;
  const Residuals with = compute_residuals(model, measured, sigma);
  ASSERT_EQ(with.cells.size(), 13u);
  const ResidualCell& cell = with.cells[0];
  ASSERT_EQ(cell.channel, static_cast<size_t>(Channel::f_lift));
  const double a = double(half) / double(n), b = 1.0 - a;  // the two halves' shares of the samples
  // MSE_w = 4 (a / 5 + b / 2); without the spread MSE = 4 and the excess is ln(4 / 1.5)
  const double mse_w = 4.0 * (a / 5.0 + b / 2.0);
  EXPECT_NEAR(none.cells[0].excess, std::log(4.0 / kNoiseAllowance), 1e-12);
  EXPECT_NEAR(cell.excess, std::log(std::max(mse_w / kNoiseAllowance, 1.0)), 1e-12);
  EXPECT_NEAR(cell.rms, 2.0, 1e-12);  // the raw residual's, as before
  EXPECT_NEAR(cell.spread, std::sqrt(4.0 * a + 1.0 * b), 1e-12);
  EXPECT_NEAR(cell.spread_share, a * 4.0 / 5.0 + b * 1.0 / 2.0, 1e-12);
  EXPECT_NEAR(with.spread_share_of(static_cast<size_t>(Channel::f_lift)), cell.spread_share, 1e-15);
  // the log-ratio's cell term: ln MSE_w plus the mean of ln w (the log-determinant), against ln 4
  EXPECT_NEAR(with.log_ratio - none.log_ratio,
              std::log(mse_w) + a * std::log(5.0) + b * std::log(2.0) - std::log(4.0), 1e-12);
  // the other channels are untouched
  EXPECT_EQ(with.excess - cell.excess, none.excess - none.cells[0].excess);
}

// the sensitivity adds to the residual's variance as it is, beside the ensemble's (1 + 1/N) v: on
// f_lift (residual ±2, σ = 1) a sensitivity s = 3 alone gives w = 4; with an ensemble's v = 3 of
// N = 3 members and s = 1, w = 1 + 4 + 1 = 6. The other channels have neither
TEST(Residuals, ASensitivityAddsToTheVarianceAsItIsBesideTheEnsembles) {
  sim2real::Run measured;
  measured.series = test::reference_series();  // no marks: one phase
  sim2real::Run model = measured;
  const size_t n = measured.series.size();
  for (size_t i = 0; i < n; ++i) measured.series[Channel::f_lift][i] += i % 2 == 0 ? 2.0 : -2.0;
  const std::vector<double> sigma(kChannelCount, 1.0);
  const Residuals none = compute_residuals(model, measured, sigma);
  auto sensitivity = [&](double s) {
    TimeSeries out;
    out[Channel::t] = model.series[Channel::t];
    for (size_t c = 1; c < kChannelCount; ++c)
      out.columns[c].assign(n, c == static_cast<size_t>(Channel::f_lift) ? s : 0.0);
    return out;
  };
  // the sensitivity alone (no ensemble: members 0)
  model.spread = RunSpread{0, {}, 2, sensitivity(3.0), {}, {}, {}, {}};
  const Residuals alone = compute_residuals(model, measured, sigma);
  EXPECT_EQ(alone.spread_members, 0);
  EXPECT_EQ(alone.sensitivity_runs, 2);
  EXPECT_TRUE(alone.judged_with_spread());
  EXPECT_NEAR(alone.cells[0].excess, std::log(std::max(4.0 / 4.0 / kNoiseAllowance, 1.0)), 1e-12);
  EXPECT_NEAR(alone.cells[0].spread, std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(alone.cells[0].spread_share, 3.0 / 4.0, 1e-12);
  EXPECT_NEAR(alone.log_ratio - none.log_ratio, std::log(1.0) + std::log(4.0) - std::log(4.0),
              1e-12);
  // both: the variances add
  model.spread = uniform_spread(model, 3, 0.0);
  for (double& v : model.spread->variance[Channel::f_lift]) v = 3.0;
  model.spread->sensitivity_runs = 4;
  model.spread->sensitivity = sensitivity(1.0);
  const Residuals both = compute_residuals(model, measured, sigma);
  EXPECT_EQ(both.spread_members, 3);
  EXPECT_EQ(both.sensitivity_runs, 4);
  EXPECT_NEAR(both.cells[0].spread, std::sqrt(5.0), 1e-12);
  EXPECT_NEAR(both.cells[0].spread_share, 5.0 / 6.0, 1e-12);
  EXPECT_NEAR(both.log_ratio - none.log_ratio, std::log(4.0 / 6.0) + std::log(6.0) - std::log(4.0),
              1e-12);
  // the other channels are untouched by either
  EXPECT_EQ(both.excess - both.cells[0].excess, none.excess - none.cells[0].excess);
  EXPECT_EQ(alone.excess - alone.cells[0].excess, none.excess - none.cells[0].excess);
  // a residual beyond the sensor noise (excess ln(4 / 1.5)) is within noise against either
  EXPECT_GT(none.excess, 0.5);
  EXPECT_EQ(alone.excess, 0.0);
  EXPECT_EQ(both.excess, 0.0);
}

// a channel whose residual is what another pile arrangement gives, drawn from a known spread: the
// measured run is one arrangement a_0 plus sensor noise, the model the mean of N = 3 others, so
// r = a_0 − ā + n with variance σ² + (1 + 1/N) v. With the spread the dig is within noise; without
// it the same residual is far beyond noise (v = 100 σ² in the dig, 0 outside it)
TEST(Residuals, AResidualAsLargeAsTheSimulationsSpreadIsWithinNoiseOnlyWithIt) {
  auto rng = fresh_rng();
  constexpr int kMembers = 3;
  constexpr double kSpreadOverNoise = 10.0;  // √v / σ in the dig
  SpreadCase k = spread_case(rng, kMembers);
  sim2real::Run &model = k.model, &measured = k.measured;
  const std::vector<double>& sigma = k.sigma;
  const auto& t = model.series[Channel::t];
  for (size_t c = 1; c < kChannelCount; ++c) {
    const double sd = kSpreadOverNoise * sigma[c];
    std::normal_distribution<double> arrangement(0.0, sd);
    for (size_t i = 0; i < t.size(); ++i) {
      if (t[i] < test::kDigStart || t[i] >= test::kDigEnd) continue;
      double mean = 0.0;
      for (int k = 0; k < kMembers; ++k) mean += arrangement(rng);
      measured.series.columns[c][i] += arrangement(rng);
      model.series.columns[c][i] += mean / kMembers;
      model.spread->variance.columns[c][i] = sd * sd;
    }
  }
  const Residuals with = compute_residuals(model, measured, sigma);
  sim2real::Run blind = model;
  blind.spread.reset();
  const Residuals without = compute_residuals(blind, measured, sigma);
  std::printf("[ measured ] a spread of %g σ in the dig: excess %.3f with it, %.3f without\n",
              kSpreadOverNoise, with.excess, without.excess);
  // within noise with it (the perfect model's bound above); without it every channel's dig cell
  // has MSE ≈ (1 + (1 + 1/3) 100) σ², excess ≈ ln(134.3 / 1.5) ≈ 4.5
  EXPECT_LT(with.excess, 0.5);
  for (const auto& cell : without.cells) {
    if (with.phases[cell.phase].name == "dig") {
      EXPECT_GT(cell.excess, 4.0) << kChannelNames[cell.channel];
    }
  }
  // the model's share of the variance in the dig: (4/3 · 100) / (1 + 4/3 · 100) ≈ 0.993
  const double share = (1.0 + 1.0 / kMembers) * kSpreadOverNoise * kSpreadOverNoise;
  for (const auto& cell : with.cells) {
    if (with.phases[cell.phase].name != "dig") continue;
    EXPECT_NEAR(cell.spread_share, share / (1.0 + share), 1e-12) << kChannelNames[cell.channel];
  }
}

// a spread made by hand wrongly is a program error that names the field
TEST(Residuals, ASpreadOffTheRunsTimesOrNegativeIsAnError) {
  sim2real::Run measured;
  measured.series = test::reference_series();
  const std::vector<double> sigma(kChannelCount, 1.0);
  sim2real::Run model = measured;
  model.spread = uniform_spread(model, 1, 0.0);
  EXPECT_THROW(compute_residuals(model, measured, sigma), Error);
  model.spread = uniform_spread(model, 2, 0.0);
  model.spread->variance[Channel::f_tilt][7] = -1.0;
  try {
    compute_residuals(model, measured, sigma);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("variance's f_tilt"), std::string::npos) << e.what();
  }
  model.spread = uniform_spread(model, 2, 0.0);
  model.spread->variance[Channel::t][3] += 1e-3;
  EXPECT_THROW(compute_residuals(model, measured, sigma), Error);
  // a spread with neither part, or a sensitivity that is negative somewhere, names what is wrong
  model.spread = RunSpread{};
  try {
    compute_residuals(model, measured, sigma);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("neither"), std::string::npos) << e.what();
  }
  model.spread = RunSpread{0, {}, 2, uniform_spread(model, 2, 0.0).variance, {}, {}, {}, {}};
  model.spread->sensitivity[Channel::f_tilt][7] = -1.0;
  try {
    compute_residuals(model, measured, sigma);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("sensitivity's f_tilt"), std::string::npos) << e.what();
  }
}

// Student's t on the normal scale: the 5 % two-sided points of t (4.303 at 2 degrees, 2.776 at 4,
// 2.228 at 10) are the normal's 1.960; infinitely many degrees change nothing; fewer degrees make a
// deviate smaller, a larger deviate stays larger
TEST(Residuals, TheGaussianEquivalentOfStudentsT) {
  EXPECT_NEAR(gaussian_equivalent(4.302653, 2.0), 1.959964, 1e-5);
  EXPECT_NEAR(gaussian_equivalent(-2.776445, 4.0), 1.959964, 1e-5);
  EXPECT_NEAR(gaussian_equivalent(2.228139, 10.0), 1.959964, 1e-5);
  EXPECT_EQ(gaussian_equivalent(3.0, HUGE_VAL), 3.0);
  EXPECT_EQ(gaussian_equivalent(-3.0, 1e8), 3.0);
  EXPECT_NEAR(gaussian_equivalent(3.0, 1e6), 3.0, 1e-5);
  EXPECT_EQ(gaussian_equivalent(0.0, 2.0), 0.0);
  EXPECT_EQ(gaussian_equivalent(HUGE_VAL, 2.0), HUGE_VAL);
  double previous = 0.0;
  for (const double dof : {1.0, 2.0, 5.0, 30.0, 1000.0}) {
    const double z = gaussian_equivalent(4.0, dof);
    EXPECT_GT(z, previous) << dof;
    EXPECT_LT(z, 4.0) << dof;
    previous = z;
  }
  EXPECT_GT(gaussian_equivalent(5.0, 2.0), gaussian_equivalent(4.0, 2.0));
  // a tail below a double's range: Wallace's approximation, monotone across the switch and not
  // capped (1000 at 10^6 degrees is about 830), near z itself where the degrees are many
  previous = 0.0;
  for (double z = 30.0; z < 50.0; z += 0.5) {
    const double e = gaussian_equivalent(z, 1e6);
    EXPECT_GE(e, previous) << z;
    EXPECT_NEAR(e, z, 0.01 * z) << z;
    previous = e;
  }
  EXPECT_GT(gaussian_equivalent(1000.0, 1e6), 500.0);
  EXPECT_GT(gaussian_equivalent(1e200, 2.0), 30.0);
  EXPECT_TRUE(std::isfinite(gaussian_equivalent(1e200, 2.0)));
  EXPECT_THROW(gaussian_equivalent(1.0, 0.0), Error);
  EXPECT_THROW(gaussian_equivalent(1.0, NAN), Error);
}

// the model's variance as a pile ensemble estimates it: at every sample of the dig the sample
// variance of three members' draws (2 degrees of freedom), a spread of 10 σ, and the measured run
// another arrangement. Judged as if that estimate were the variance, the dig's mean square is
// about 4 times the noise (E[1/v̂] ≫ 1/v where v̂ falls short by chance: far beyond noise in every
// channel); judged by Student's t with the estimate's 2 degrees, about 1.3 (within the allowance
// κ = 1.5: the share in Satterthwaite's rule is itself estimated, which leaves it above 1). Over
// 800 simulated runs the 13 channels' mean was at most 1.54 by t and at least 3.75 without
TEST(Residuals, AVarianceFromThreeMembersIsJudgedByStudentsT) {
  auto rng = fresh_rng();
  constexpr int kMembers = 3;
  constexpr double kSpreadOverNoise = 10.0;
  SpreadCase k = spread_case(rng, kMembers);
  sim2real::Run &model = k.model, &measured = k.measured;
  const std::vector<double>& sigma = k.sigma;
  const auto& t = model.series[Channel::t];
  for (size_t c = 1; c < kChannelCount; ++c) {
    std::normal_distribution<double> arrangement(0.0, kSpreadOverNoise * sigma[c]);
    for (size_t i = 0; i < t.size(); ++i) {
      if (t[i] < test::kDigStart || t[i] >= test::kDigEnd) continue;
      double x[kMembers], mean = 0.0, square = 0.0;
      for (double& v : x) mean += (v = arrangement(rng)) / kMembers;
      for (const double v : x) square += (v - mean) * (v - mean);
      measured.series.columns[c][i] += arrangement(rng);
      model.series.columns[c][i] += mean;
      model.spread->variance.columns[c][i] = square / (kMembers - 1);
    }
  }
  const Residuals gaussian = compute_residuals(model, measured, sigma);
  model.spread->variance_dof.assign(kChannelCount, double(kMembers - 1));
  const Residuals t_judged = compute_residuals(model, measured, sigma);
  // the dig cells' mean square in units of σ², from the log-ratio and the cell's mean ln w
  const auto dig_mean_square = [&](const Residuals& res) {
    double sum = 0.0;
    int cells = 0;
    const auto& tm = measured.series[Channel::t];
    for (const auto& cell : res.cells) {
      if (res.phases[cell.phase].name != "dig") continue;
      double log_w = 0.0;
      int n = 0;
      for (size_t i = 0; i < tm.size(); ++i) {
        if (tm[i] < test::kDigStart || tm[i] >= test::kDigEnd) continue;
        log_w += std::log(1.0 + (1.0 + 1.0 / kMembers) *
                                    model.spread->variance.columns[cell.channel][i] /
                                    (sigma[cell.channel] * sigma[cell.channel]));
        ++n;
      }
      EXPECT_EQ(n, cell.samples);
      sum += std::exp(cell.log_ratio - log_w / n);
      ++cells;
    }
    return sum / cells;
  };
  const double g = dig_mean_square(gaussian), s = dig_mean_square(t_judged);
  std::printf(
      "[ measured ] dig mean square / sigma^2: %.2f judged as known, %.2f by Student's t; "
      "run excess %.2f and %.2f\n",
      g, s, gaussian.excess, t_judged.excess);
  EXPECT_GT(g, 2.5);
  EXPECT_LT(s, 1.8);
  EXPECT_GT(s, 0.8);
  EXPECT_LT(t_judged.excess, gaussian.excess / 4.0);
  // outside the dig the spread is zero: those cells are the sensor law's, with or without degrees
  for (size_t k = 0; k < gaussian.cells.size(); ++k) {
    if (gaussian.phases[gaussian.cells[k].phase].name == "dig") continue;
    EXPECT_EQ(gaussian.cells[k].log_ratio, t_judged.cells[k].log_ratio);
  }
}

// the 99 % point of a mean square of n standard normal samples
TEST(Residuals, TheNoiseQuantileOfAMeanSquare) {
  EXPECT_NEAR(noise_quantile(1.0), 6.634897, 1e-5);
  EXPECT_NEAR(noise_quantile(10.0), 2.320925, 1e-5);
  EXPECT_NEAR(noise_quantile(55.0), 1.496220, 1e-5);
  EXPECT_NEAR(noise_quantile(1000.0), 1.106969, 1e-5);
  EXPECT_GT(noise_quantile(1.5), noise_quantile(2.0));  // an effective count, not an integer
  EXPECT_THROW(noise_quantile(0.0), Error);
}

// a spread whose departures last the whole dig (each pile fills the bucket differently: an
// offset over the phase) leaves one independent number per cell under the null, and a residual
// that is one such draw is judged with the allowance of one sample. Ten runs of 13 channels, each
// dig cell offset by one draw from a spread of 10 σ: judged as if the dig's samples were
// independent, about a fifth of the cells (P(χ²₁ > 1.5) = 0.22) are beyond noise; with the
// departures' τ, about one in a hundred
TEST(Residuals, ACellHoldsAsManySamplesUnderTheNullAsItsSpreadDecorrelates) {
  auto rng = fresh_rng();
  constexpr int kMembers = 3, kRuns = 10;
  constexpr double kSpreadOverNoise = 10.0;
  int beyond_white = 0, beyond_null = 0, cells = 0;
  for (int run = 0; run < kRuns; ++run) {
    SpreadCase k = spread_case(rng, kMembers);
    sim2real::Run &model = k.model, &measured = k.measured;
    const std::vector<double>& sigma = k.sigma;
    const auto& t = model.series[Channel::t];
    for (size_t c = 1; c < kChannelCount; ++c) {
      const double sd = kSpreadOverNoise * sigma[c];
      // one draw of the mean's error and one of the measured pile, held over the dig
      std::normal_distribution<double> arrangement(0.0, sd);
      const double offset = arrangement(rng) - arrangement(rng) / std::sqrt(double(kMembers));
      for (size_t i = 0; i < t.size(); ++i) {
        if (t[i] < test::kDigStart || t[i] >= test::kDigEnd) continue;
        measured.series.columns[c][i] += offset;
        model.spread->variance.columns[c][i] = sd * sd;
      }
    }
    const Residuals white = compute_residuals(model, measured, sigma);
    model.spread->variance_tau.assign(kChannelCount, 1e6);  // longer than any cell
    const Residuals null = compute_residuals(model, measured, sigma);
    for (size_t k = 0; k < white.cells.size(); ++k) {
      if (white.phases[white.cells[k].phase].name != "dig") continue;
      const ResidualCell& w = white.cells[k];
      const ResidualCell& n = null.cells[k];
      // white departures: κ and every sample; correlated ones: about one sample, and the
      // allowance of one among the dig's 600: κ · 6.63 / 1.14
      EXPECT_EQ(w.allowance, kNoiseAllowance);
      EXPECT_EQ(w.null_samples, double(w.samples));
      EXPECT_LT(n.null_samples, 1.05);
      EXPECT_NEAR(n.allowance,
                  kNoiseAllowance * noise_quantile(n.null_samples) / noise_quantile(n.samples),
                  1e-9);
      EXPECT_GT(n.allowance, 8.0);
      // the log-ratio does not use the allowance
      EXPECT_EQ(w.log_ratio, n.log_ratio);
      beyond_white += w.excess > 0.0;
      beyond_null += n.excess > 0.0;
      ++cells;
    }
  }
  std::printf(
      "[ measured ] dig cells beyond noise: %d of %d judged as white, %d with the null's samples\n",
      beyond_white, cells, beyond_null);
  EXPECT_GE(beyond_white, 10);
  EXPECT_LE(beyond_null, 6);
}

// degrees of freedom or correlation times made by hand wrongly are a program error naming the
// field
TEST(Residuals, DegreesOfFreedomOffTheChannelsOrNotPositiveAreAnError) {
  sim2real::Run measured;
  measured.series = test::reference_series();
  const std::vector<double> sigma(kChannelCount, 1.0);
  sim2real::Run model = measured;
  model.spread = uniform_spread(model, 3, 1.0);
  model.spread->variance_dof.assign(3, 2.0);
  EXPECT_THROW(compute_residuals(model, measured, sigma), Error);
  model.spread->variance_dof.assign(kChannelCount, 2.0);
  model.spread->variance_dof[static_cast<std::size_t>(Channel::f_tilt)] = 0.0;
  try {
    compute_residuals(model, measured, sigma);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("variance_dof's f_tilt"), std::string::npos) << e.what();
  }
  model.spread->variance_dof.assign(kChannelCount, 2.0);
  EXPECT_NO_THROW(compute_residuals(model, measured, sigma));
  // and correlation times: one per channel, at least one sample
  model.spread->variance_tau.assign(kChannelCount, 0.5);
  try {
    compute_residuals(model, measured, sigma);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("variance_tau's f_lift"), std::string::npos) << e.what();
  }
  model.spread->variance_tau.assign(2, 3.0);
  EXPECT_THROW(compute_residuals(model, measured, sigma), Error);
  model.spread->variance_tau.assign(kChannelCount, 3.0);
  EXPECT_NO_THROW(compute_residuals(model, measured, sigma));
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
