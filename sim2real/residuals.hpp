// Residuals of a simulated run against a measured one, per channel and phase (issue 6, SPEC §6):
// how far the simulation departs from the data, in units of the data's own sensor noise, so that
// "explained" and "unexplained" mean something measurable.
//
// Noise: each measured channel's noise σ is estimated from the data alone, from its second
// differences. For white noise n of variance σ², Δ²n = n[i+1] − 2n[i] + n[i−1] has variance 6σ²;
// a smooth signal sampled at 100 Hz adds almost nothing to Δ², and the robust scale (1.4826 times
// the median absolute deviation) ignores the few samples where the signal bends sharply (a
// command's ramp, a contact). Channels with fast physics of their own (particle forces) read as
// noisier than their sensor: the estimate errs on the side of calling a residual noise.
//
// Excess: in a cell (channel c, phase p) with mean-square residual MSE and noise σ_c, the excess
// is e = ln max(MSE / (κ σ_c²), 1), κ = kNoiseAllowance. A perfect model leaves MSE ≈ σ² and e = 0;
// a residual twice the noise leaves e = ln(4/κ) ≈ 1. The excess of a run is the sum over its
// cells; it is the quantity the loop fits effects to and calls explained or not.
//
// The simulation's own spread (issue 17): a simulated run that is the mean of a pile ensemble
// (sim2real/replay.hpp) carries its members' variance v_c(t) (Run::spread). A measured dig is one
// pile arrangement: y = f(θ*) + a + n, with a the arrangement's departure from the mean dig
// (variance v, the spread the simulation shows between its own piles, if it is right) and n the
// sensor noise (σ²). The ensemble's mean is m = f(θ) + ā with ā the mean of N independent
// arrangements (variance v/N). At the true parameter the residual r = y − m has mean zero and
// variance σ² + v + v/N = σ² + (1 + 1/N) v, so each sample i is judged against that: with the
// sample's variance in units of the sensor's, w_i = 1 + (1 + 1/N) v_c(t_i) / σ_c², a cell's mean
// square becomes MSE_w = (1/n) Σ r_i² / w_i (the residual in units of the sensor noise it would
// have if the piles agreed), and
//   excess     e = ln max(MSE_w / (κ σ²), 1)
//   log_ratio    Σ (n_cell / n) [ln(MSE_w / σ²) + (1/n_cell) Σ ln w_i]
// The second term of the log-ratio is the Gaussian likelihood's log-determinant: without it a
// parameter that makes the digging more chaotic would fit better merely by widening its own
// spread. Without a spread w_i = 1 exactly: r²/1, ln 1 = 0 and the numbers are today's, bit for
// bit. The cell's rms and mean stay the raw residual's (channel units), as the report prints.
// Where v is estimated from few members it is pooled over a short window first (see
// ensemble_variance in sim2real/replay.hpp: the division by a 2-degree-of-freedom estimate would
// otherwise blow up wherever the members agree by chance).
//
// The simulation's sensitivity (issue 17): a run simulated with fitted parameters θ̂ may also carry
// s_c(t), the mean square departure from it of simulations at parameters within the fit's
// uncertainty (RunSpread::sensitivity, sim2real/diagnose.hpp). Measured = f(θ*) + a + n, simulated
// = f(θ̂) + â: the parameter's error f(θ*) − f(θ̂) and, where the simulation is chaotic in its
// parameter, the two realisations' difference a − â are what s estimates, so it adds as it is:
// each sample is judged against σ² + (1 + 1/N) v + s, through the same w and the same formulas
// (N = 0, no ensemble: σ² + s).
//
// A variance estimated from few numbers (issue 17): the ensemble's v and the sensitivity's s are
// each the pooled mean square of a few runs' departures, which stay correlated longer than the
// pooling window, so each carries ν degrees of freedom (RunSpread::variance_dof, sensitivity_dof;
// ensemble_dof in sim2real/replay.hpp: about 2 for three piles on HD27). Dividing by such an
// estimate is not dividing by the variance: r / √(σ² + m̂) follows Student's t, not the normal law,
// and where m̂ falls short by chance the Gaussian judgement reads noise as excess (a 2-degree
// estimate of a spread 100 times the sensor variance makes the mean of z² about 4, not 1). So each
// sample's standardised residual z = r / (σ √w) is judged by its t law and counted on the normal
// scale the excess was made for: z' = gaussian_equivalent(z, ν_i), the normal deviate with the
// same two-sided tail probability, ν_i by Satterthwaite's rule for σ² (known exactly) plus the
// estimates m_k (k: ensemble, sensitivity), ν_i = (σ² + m_i)² / Σ_k (m_k,i² / ν_k). MSE_w and the
// effective samples then use σ² z'² for r² / w. Without degrees of freedom (a run judged against
// the sensor alone, or a spread without them) z' = z exactly. Measured on HD27-G400 pile data with
// the true effect (docs/sim2real.md "Judged by Student's t"): the run excess of the null falls
// about threefold; the verdict is not yet right with three piles (a dig whose fill lies outside
// all three members stays beyond noise).
//
// A cell's samples under the null (issue 17): the allowance κ is a margin over a mean square of
// many independent samples (its 99 % point is 1.14 for 600 white samples). Where the model's
// spread dominates a cell and its departures last the whole cell (one pile's fill: an offset over
// the after phase), the cell's residual under the null is about one independent number, whose
// square exceeds 1.5 one time in five, and the verdict takes the worst of several runs. So each
// cell counts the samples it holds under the null, n_null = n / (1 + Σ_k mean(share_k²) (τ_k − 1))
// (k: the ensemble's and the sensitivity's parts, share_k their share of each sample's variance,
// τ_k how long their departures stay correlated, RunSpread::variance_tau and sensitivity_tau,
// held to [1, n]: Bartlett's variance of a mean square, with Σ ρ² taken as Σ ρ), and is judged
// with the allowance κ max(1, noise_quantile(n_null) / noise_quantile(n)): κ where the samples are
// independent, widened by as much as the null's 99 % point widens where they are not (8.7 for one
// null sample among 600). The log-ratio (the fits' objective) does not use it. Without a spread,
// or with τ = 1, the allowance is κ exactly.
//
// Correlated residuals (issue 17): the log-ratio counts every sample as independent, but a dig's
// residual is correlated in time (two pile arrangements' forces over about 0.1 s, a misfit over a
// whole phase), so n samples carry the information of fewer. Each cell records its effective
// samples n_eff = n / τ, τ the integrated autocorrelation time of the standardised residual r/√w
// in the cell (z' where the variance has degrees of freedom, above): the variance of a mean of
// correlated samples is τ times that of independent ones
// (the discovery's regression inflates its intervals by the same law, sim2real/discovery.hpp).
// The diagnosis weighs each cell's log-ratio by n_eff where it measures the fit's uncertainty
// (sim2real/diagnose.cpp, the sensitivity's curvature).
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "sim2real/timeseries.hpp"

namespace talus::sim2real {

// a residual whose mean square is up to κ = 1.5 times the noise variance counts as noise: room for
// the ±10 % error of σ estimated from about a thousand samples and for the interpolation of a
// simulation logged at 100 Hz from 20 ms steps (docs/sim2real.md)
inline constexpr double kNoiseAllowance = 1.5;

// the integrated autocorrelation time τ = 1 + 2 Σ_{k≥1} ρ_k of a series, in samples: ρ_k its
// uncentred autocorrelation at lag k (Σ z_i z_{i+k} / Σ z_i², pairs within one segment only;
// `segment` labels each sample's run, empty: one), summed by Geyer's initial monotone sequence
// (the pair sums Γ_m = ρ_2m + ρ_2m+1 while they stay positive, each held to the one before: C. J.
// Geyer, "Practical Markov chain Monte Carlo", Statistical Science 7, 1992, section 3.3), which
// stops where the long lags' estimates turn to noise (a fixed window runs away on a few hundred
// samples of white noise: τ up to 5 was seen); held to [1, n]. The variance of a mean of the
// samples is τ times that of as many independent ones, so they count as n/τ (at least one).
// Uncentred: an offset over the whole series is correlation, and counts as one sample; so does a
// small one, steeply: white noise of 600 samples with an offset of b σ counts 470-600 at b = 0,
// 110-520 at 0.2, 14-130 at 0.3, 5-8 at 0.5 and 2 at 1 (an offset of 0.3 σ over 600 samples is 7
// standard errors, a misfit, though within the excess's allowance). A series holding NaN or ∞
// gives 1
double integrated_autocorrelation_time(const std::vector<double>& z,
                                       const std::vector<int>& segment = {});

// the quantile of the noise's mean square the allowance follows: a cell's mean square of n
// independent standard normal samples exceeds noise_quantile(n) = χ²_n(0.99) / n once in a hundred
inline constexpr double kAllowanceQuantile = 0.99;
// χ²_samples(kAllowanceQuantile) / samples, for samples > 0 (not an integer: an effective count);
// Error otherwise. 6.63 for 1, 2.32 for 10, 1.50 at 55, 1.11 at 1,000
double noise_quantile(double samples);

// the normal deviate with the same two-sided tail probability as |z| under Student's t with `dof`
// degrees of freedom: |z| itself for infinite dof (or above 1e7, where the two agree to 1e-7),
// smaller the fewer the degrees (z = 4.303 is 1.960 at 2 degrees, both the 5 % two-sided point);
// where the tail is below the smallest normal double, Wallace's approximation (never capped).
// Error for dof ≤ 0 or NaN; a non-finite z is returned as its magnitude
double gaussian_equivalent(double z, double dof);

// the noise standard deviation of a uniformly sampled signal (at least 3 samples), never below
// 1e-6 of its largest magnitude (noise-free data would otherwise make any residual infinite)
double noise_sigma(const std::vector<double>& x);
// σ of every channel of a measured run (index as kChannelNames; t's entry is 0)
std::vector<double> noise_sigmas(const TimeSeries& measured);

// a phase of a run: approach [start, dig_start), dig [dig_start, dig_end), after [dig_end, end];
// a run without phase marks is one phase, "run"
struct Phase {
  std::string name;
  double t0 = 0.0, t1 = 0.0;  // s
};
std::vector<Phase> run_phases(const Run& measured);

struct ResidualCell {
  std::size_t channel = 0;  // index into kChannelNames
  std::size_t phase = 0;    // index into the phases
  int samples = 0;
  double rms = 0.0;         // root-mean-square residual, measured minus simulated [channel unit]
  double mean = 0.0;        // mean residual [channel unit]
  double sigma = 0.0;       // the measured channel's noise [channel unit]
  double excess = 0.0;      // ln max(MSE_w / (κ σ²), 1); MSE_w = MSE without a spread
  // the simulation's own spread over the cell, zero without one: sqrt of the cell's mean of
  // m = (1 + 1/N) v + s [channel unit], and the model's mean share of the variance each sample is
  // judged against, m / (σ² + m), in [0, 1)
  double spread = 0.0;
  double spread_share = 0.0;
  // the cell's term of the log-likelihood: ln max(MSE_w / σ², 1e-6) + the mean of ln w
  double log_ratio = 0.0;
  // the samples the cell holds under the null, n / (1 + Σ_k mean(share_k²) (τ_k − 1)), and the
  // allowance its excess was judged with, κ max(1, noise_quantile(null) / noise_quantile(n)):
  // κ itself, and null = samples, without a spread (the header comment)
  double null_samples = 0.0;
  double allowance = kNoiseAllowance;
  // samples / τ, τ the integrated autocorrelation time of r/√w over the cell's samples
  // (integrated_autocorrelation_time: uncentred, an offset is part of what is correlated)
  double effective_samples = 0.0;
};

struct Residuals {
  std::vector<Phase> phases;
  std::vector<ResidualCell> cells;  // channel-major: (f_lift, phase 0), (f_lift, phase 1), ...
  double excess = 0.0;              // summed over the cells
  // Σ (n_cell / n) ln(MSE / σ²) over the cells, not floored: the Gaussian log-likelihood with one
  // variance per cell up to constants and a factor n/2 per channel, which fits take as their
  // objective (the floored excess is flat near the optimum and would leave a parameter anywhere
  // within the noise)
  double log_ratio = 0.0;
  // N of the simulated run's spread the residual was judged with; 0: none (the sensor noise alone)
  int spread_members = 0;
  // the degrees of freedom of that ensemble's variance per channel (RunSpread::variance_dof);
  // empty: known exactly, or no ensemble
  std::vector<double> variance_dof;
  // the simulations behind the sensitivity it was judged with too; 0: none
  int sensitivity_runs = 0;
  // whether any model variance (ensemble or sensitivity) judged it
  bool judged_with_spread() const { return spread_members > 0 || sensitivity_runs > 0; }
  // the excess of the cells of these channels (an effect's signature)
  double excess_of(const std::vector<std::size_t>& channels) const;
  // a channel's spread_share averaged over its cells' samples (0 without a spread)
  double spread_share_of(std::size_t channel) const;
};

// the simulated run interpolated at the measured times of each phase (InputError when it does
// not cover them); sigma from noise_sigmas(measured). A simulated run with a spread (Run::spread)
// is judged against σ² + (1 + 1/N) v + s per sample (the header comment); a spread with neither
// part, one of one member, one not on the run's own sample times, or one holding a negative or
// non-finite variance is an Error
Residuals compute_residuals(const Run& simulated, const Run& measured, const std::vector<double>& sigma);

// the residual series of one channel at the measured times (measured minus simulated)
std::vector<double> residual_series(const Run& simulated, const Run& measured, std::size_t channel);

// what a channel's residual moves with: the measured quantity (a channel, or one derived from the
// channels: lift and tilt rates, hydraulic power, drive acceleration) whose Pearson correlation
// with the residual is the largest in magnitude
struct Correlate {
  std::string quantity;
  double r = 0.0;
};
Correlate strongest_correlate(const std::vector<double>& residual, const Run& measured);

}  // namespace talus::sim2real
