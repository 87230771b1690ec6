#include "sim2real/residuals.hpp"

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <cfloat>
#include <cmath>
#include <utility>

#include "host/error.hpp"

namespace talus::sim2real {

namespace {

// 1.4826 MAD estimates σ of a normal distribution (the MAD of N(0, σ²) is 0.6745 σ)
constexpr double kMadToSigma = 1.4826;
// the floor of σ relative to the channel's largest magnitude (see noise_sigma)
constexpr double kSigmaFloor = 1e-6;
// and never below this, in the channel's SI unit, for a channel that is zero throughout (its σ²
// must stay a normal double: 1e-300 squared underflows to 0 and makes the excess NaN)
constexpr double kSigmaAbsoluteFloor = 1e-12;
// above this many degrees of freedom Student's t is the normal law to better than 1e-7 in its
// deviates (the t quantile's expansion: z (1 + (z² + 1) / (4ν) + ...)), so it is judged as one
constexpr double kGaussianDof = 1e7;
// derivatives of measured channels by central differences over ±this many samples (0.2 s at
// 100 Hz): long enough that 1 mm of stroke noise makes only 7 mm/s of rate noise
constexpr int kDerivativeHalfWidth = 10;

double median(std::vector<double> v) {
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  return v[mid];
}

// d/dt by central differences over ±k samples (one-sided at the ends)
std::vector<double> derivative(const std::vector<double>& t, const std::vector<double>& x) {
  const int n = static_cast<int>(x.size());
  std::vector<double> d(n, 0.0);
  for (int i = 0; i < n; ++i) {
    const int a = std::max(0, i - kDerivativeHalfWidth), b = std::min(n - 1, i + kDerivativeHalfWidth);
    if (b > a) d[i] = (x[b] - x[a]) / (t[b] - t[a]);
  }
  return d;
}

double pearson(const std::vector<double>& a, const std::vector<double>& b) {
  const size_t n = a.size();
  double ma = 0.0, mb = 0.0;
  for (size_t i = 0; i < n; ++i) ma += a[i], mb += b[i];
  ma /= n;
  mb /= n;
  double sab = 0.0, saa = 0.0, sbb = 0.0;
  for (size_t i = 0; i < n; ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return saa > 0.0 && sbb > 0.0 ? sab / std::sqrt(saa * sbb) : 0.0;
}

}  // namespace

double noise_sigma(const std::vector<double>& x) {
  if (x.size() < 3) throw Error("noise_sigma: needs at least 3 samples");
  std::vector<double> d2(x.size() - 2);
  double largest = 0.0;
  for (size_t i = 0; i < x.size(); ++i) largest = std::max(largest, std::abs(x[i]));
  for (size_t i = 1; i + 1 < x.size(); ++i) d2[i - 1] = x[i + 1] - 2.0 * x[i] + x[i - 1];
  const double centre = median(d2);
  for (double& v : d2) v = std::abs(v - centre);
  const double sigma = kMadToSigma * median(d2) / std::sqrt(6.0);
  return std::max(sigma, std::max(kSigmaFloor * largest, kSigmaAbsoluteFloor));
}

double noise_quantile(double samples) {
  if (!(samples > 0.0))
    throw Error("noise_quantile: " + message_number(samples) + " samples; give more than 0");
  return boost::math::quantile(boost::math::chi_squared(samples), kAllowanceQuantile) / samples;
}

double gaussian_equivalent(double z, double dof) {
  if (!(dof > 0.0))
    throw Error("gaussian_equivalent: " + message_number(dof) +
                " degrees of freedom; give more than 0");
  const double magnitude = std::abs(z);
  if (!std::isfinite(magnitude) || dof > kGaussianDof) return magnitude;
  // the upper tail under t, then the normal deviate with that tail
  const double tail = boost::math::cdf(complement(boost::math::students_t(dof), magnitude));
  if (tail > DBL_MIN) return boost::math::quantile(complement(boost::math::normal(), tail));
  // a tail below the smallest normal double: Wallace's approximation of the deviate (D. L.
  // Wallace, "Bounds on normal approximations to Student's and the chi-square distributions",
  // Ann. Math. Statist. 30, 1959), which tends to |z| as the degrees grow, held at least at the
  // deviate of the smallest tail so that the mapping stays monotone
  // ln(1 + z²/ν), written so that z² cannot overflow
  const double ratio = magnitude / std::sqrt(dof);
  const double log_term = ratio > 1.0 ? 2.0 * std::log(ratio) + std::log1p(1.0 / (ratio * ratio))
                                      : std::log1p(ratio * ratio);
  const double wallace = std::sqrt(dof * log_term) * (8.0 * dof + 1.0) / (8.0 * dof + 3.0);
  return std::max(wallace, boost::math::quantile(complement(boost::math::normal(), DBL_MIN)));
}

std::vector<double> noise_sigmas(const TimeSeries& measured) {
  std::vector<double> sigma(kChannelCount, 0.0);
  for (size_t c = 1; c < kChannelCount; ++c) sigma[c] = noise_sigma(measured.columns[c]);
  return sigma;
}

std::vector<Phase> run_phases(const Run& measured) {
  const auto& t = measured.series[Channel::t];
  const double start = t.front(), end = t.back();
  const auto& s = measured.summary;
  if (!s.dig_start_s || !s.dig_end_s || !(*s.dig_end_s > *s.dig_start_s)) return {{"run", start, end}};
  std::vector<Phase> phases;
  // the digging phase's ends belong to it; a phase needs samples of its own to count
  const double d0 = std::clamp(*s.dig_start_s, start, end), d1 = std::clamp(*s.dig_end_s, start, end);
  if (d0 > start) phases.push_back({"approach", start, d0});
  phases.push_back({"dig", d0, d1});
  if (d1 < end) phases.push_back({"after", d1, end});
  return phases;
}

namespace {

// a column on the simulation's sample times (a channel, or its spread's variance) at the measured
// times: linear between the simulation's samples, as the run itself is read; InputError when the
// simulation does not cover the measurement
std::vector<double> at_measured_times(const Run& simulated, const std::vector<double>& column,
                                      const Run& measured) {
  const auto& tm = measured.series[Channel::t];
  const auto& ts = simulated.series[Channel::t];
  if (ts.empty() || ts.front() > tm.front() + 1e-9 || ts.back() < tm.back() - 1e-9)
    throw InputError("the simulation of " + measured.dir.string() + " covers " +
                     (ts.empty() ? std::string("nothing") : std::to_string(ts.front()) + "-" + std::to_string(ts.back()) + " s") +
                     " but the measurement " + std::to_string(tm.front()) + "-" + std::to_string(tm.back()) +
                     " s; the scenario's duration must cover the measured run");
  std::vector<double> at(tm.begin(), tm.end());
  for (double& v : at) v = std::clamp(v, ts.front(), ts.back());
  return interpolate(ts, column, at);
}

// a spread holds an ensemble's variance (two or more members), a sensitivity (one or more
// simulations), or both, each on the run's own sample times, finite and non-negative everywhere;
// it is made by code (ensemble_mean, the diagnosis), so a bad one is a program error, named by its
// field
void check_variance(const Run& simulated, const TimeSeries& variance, const std::string& which) {
  if (variance[Channel::t] != simulated.series[Channel::t])
    throw Error(which +
                "'s t is not the run's sample times; compute it from the simulations the run "
                "is judged with");
  for (std::size_t c = 1; c < kChannelCount; ++c) {
    const auto& v = variance.columns[c];
    if (v.size() != simulated.series.size())
      throw Error(which + "'s " + std::string(kChannelNames[c]) + " has " +
                  std::to_string(v.size()) + " samples for the run's " +
                  std::to_string(simulated.series.size()));
    for (std::size_t i = 0; i < v.size(); ++i)
      if (!std::isfinite(v[i]) || v[i] < 0.0)
        throw Error(which + "'s " + std::string(kChannelNames[c]) + " is " + message_number(v[i]) +
                    " at t = " + message_number(variance[Channel::t][i]) +
                    " s; a variance is finite and at least 0");
  }
}

// degrees of freedom: none (known exactly) or one per channel, each above 0 (t's entry ignored)
void check_dof(const std::vector<double>& dof, const std::string& which) {
  if (dof.empty()) return;
  if (dof.size() != kChannelCount)
    throw Error(which + " has " + std::to_string(dof.size()) + " entries for " +
                std::to_string(kChannelCount) +
                " channels; compute it with ensemble_dof or sensitivity_dof");
  for (std::size_t c = 1; c < kChannelCount; ++c)
    if (!(dof[c] > 0.0))
      throw Error(which + "'s " + std::string(kChannelNames[c]) + " is " + message_number(dof[c]) +
                  "; degrees of freedom are above 0 (or leave them empty: known exactly)");
}

// correlation times: none (white) or one per channel, each finite and at least 1 sample
void check_tau(const std::vector<double>& tau, const std::string& which) {
  if (tau.empty()) return;
  if (tau.size() != kChannelCount)
    throw Error(which + " has " + std::to_string(tau.size()) + " entries for " +
                std::to_string(kChannelCount) +
                " channels; compute it with ensemble_departure_time or sensitivity_departure_time");
  for (std::size_t c = 1; c < kChannelCount; ++c)
    if (!(tau[c] >= 1.0) || !std::isfinite(tau[c]))
      throw Error(
          which + "'s " + std::string(kChannelNames[c]) + " is " + message_number(tau[c]) +
          "; a correlation time is finite and at least 1 sample (or leave it empty: white)");
}

void check_spread(const Run& simulated) {
  const RunSpread& s = *simulated.spread;
  const std::string which =
      "compute_residuals: the simulated run " + simulated.label() + "'s spread";
  if (s.members == 1 || s.members < 0)
    throw Error(
        which + " has members = " + std::to_string(s.members) +
        "; an ensemble's spread comes from 2 or more (ensemble_mean), else set members to 0");
  if (s.sensitivity_runs < 0)
    throw Error(which + " has sensitivity_runs = " + std::to_string(s.sensitivity_runs) +
                "; give the simulations behind the sensitivity, or 0 for none");
  if (s.members == 0 && s.sensitivity_runs == 0)
    throw Error(which +
                " has neither an ensemble (members 0) nor a sensitivity (sensitivity_runs 0); "
                "leave the spread empty instead");
  if (s.members > 0) check_variance(simulated, s.variance, which + ": variance");
  if (s.sensitivity_runs > 0) check_variance(simulated, s.sensitivity, which + ": sensitivity");
  check_dof(s.variance_dof, which + ": variance_dof");
  check_dof(s.sensitivity_dof, which + ": sensitivity_dof");
  check_tau(s.variance_tau, which + ": variance_tau");
  check_tau(s.sensitivity_tau, which + ": sensitivity_tau");
}

}  // namespace

std::vector<double> residual_series(const Run& simulated, const Run& measured,
                                    std::size_t channel) {
  const auto& tm = measured.series[Channel::t];
  const auto sim = at_measured_times(simulated, simulated.series.columns[channel], measured);
  std::vector<double> r(tm.size());
  for (size_t i = 0; i < tm.size(); ++i) r[i] = measured.series.columns[channel][i] - sim[i];
  return r;
}

Residuals compute_residuals(const Run& simulated, const Run& measured, const std::vector<double>& sigma) {
  Residuals out;
  out.phases = run_phases(measured);
  const auto& tm = measured.series[Channel::t];
  if (simulated.spread) {
    check_spread(simulated);
    out.spread_members = simulated.spread->members;
    if (out.spread_members > 0) out.variance_dof = simulated.spread->variance_dof;
    out.sensitivity_runs = simulated.spread->sensitivity_runs;
  }
  // the measured run stands for one more arrangement and the mean has its own error: (1 + 1/N) v
  const double inflation = out.spread_members > 0 ? 1.0 + 1.0 / out.spread_members : 0.0;
  for (size_t c = 1; c < kChannelCount; ++c) {
    const std::vector<double> r = residual_series(simulated, measured, c);
    // the model's variance per sample, (1 + 1/N) v + s, and the sample's variance in units of
    // the sensor's, w = 1 + ((1 + 1/N) v + s) / σ²: exactly 1 without a spread
    std::vector<double> model(tm.size(), 0.0), w(tm.size(), 1.0);
    // and each sample's standardised residual on the normal scale [channel unit] (the header
    // comment; r/√w itself without degrees of freedom) and its square, what MSE_w sums
    std::vector<double> standard(r), square(tm.size());
    for (size_t i = 0; i < tm.size(); ++i) square[i] = r[i] * r[i];
    // each estimate's share of the sample's variance, and how long its departures stay correlated
    // [samples]: what a cell's null samples count (the header comment)
    std::vector<double> share_v(tm.size(), 0.0), share_s(tm.size(), 0.0);
    double tau_v = 1.0, tau_s = 1.0;
    if (simulated.spread) {
      const RunSpread& spread = *simulated.spread;
      if (!spread.variance_tau.empty()) tau_v = spread.variance_tau[c];
      if (!spread.sensitivity_tau.empty()) tau_s = spread.sensitivity_tau[c];
      // Satterthwaite's denominator Σ m_k² / ν_k of the model variance (0: known exactly)
      std::vector<double> unknown(tm.size(), 0.0);
      if (out.spread_members > 0) {
        const auto v = at_measured_times(simulated, spread.variance.columns[c], measured);
        const double dof = spread.variance_dof.empty() ? HUGE_VAL : spread.variance_dof[c];
        for (size_t i = 0; i < tm.size(); ++i) {
          model[i] = inflation * v[i];
          unknown[i] += model[i] * model[i] / dof;
          share_v[i] = model[i];
        }
      }
      if (out.sensitivity_runs > 0) {
        const auto sv = at_measured_times(simulated, spread.sensitivity.columns[c], measured);
        const double dof = spread.sensitivity_dof.empty() ? HUGE_VAL : spread.sensitivity_dof[c];
        for (size_t i = 0; i < tm.size(); ++i) {
          model[i] += sv[i];
          unknown[i] += sv[i] * sv[i] / dof;
          share_s[i] = sv[i];
        }
      }
      const double noise = sigma[c] * sigma[c];
      for (size_t i = 0; i < tm.size(); ++i) {
        w[i] = 1.0 + model[i] / noise;
        share_v[i] /= noise + model[i];
        share_s[i] /= noise + model[i];
        standard[i] = r[i] / std::sqrt(w[i]);
        square[i] = r[i] * r[i] / w[i];
        if (!(unknown[i] > 0.0)) continue;
        // Satterthwaite's ν of σ² + m, σ² known exactly: (σ² + m)² / Σ m_k² / ν_k
        const double dof = (noise + model[i]) * (noise + model[i]) / unknown[i];
        standard[i] =
            std::copysign(sigma[c] * gaussian_equivalent(standard[i] / sigma[c], dof), r[i]);
        square[i] = standard[i] * standard[i];
      }
    }
    for (size_t p = 0; p < out.phases.size(); ++p) {
      // samples of the phase: [t0, t1) except the last phase, which keeps its end
      const Phase& ph = out.phases[p];
      const bool last = p + 1 == out.phases.size();
      ResidualCell cell;
      cell.channel = c;
      cell.phase = p;
      cell.sigma = sigma[c];
      double sum = 0.0, sum2 = 0.0, sum2w = 0.0, sum_log_w = 0.0, sum_model = 0.0, sum_share = 0.0,
             sum_share_v2 = 0.0, sum_share_s2 = 0.0;
      std::vector<double> z;  // the standardised residual over the cell
      for (size_t i = 0; i < tm.size(); ++i) {
        if (tm[i] < ph.t0 || tm[i] > ph.t1 || (!last && tm[i] >= ph.t1)) continue;
        z.push_back(standard[i]);
        sum += r[i];
        sum2 += r[i] * r[i];
        sum2w += square[i];
        sum_log_w += std::log(w[i]);
        sum_model += model[i];
        sum_share += (w[i] - 1.0) / w[i];
        sum_share_v2 += share_v[i] * share_v[i];
        sum_share_s2 += share_s[i] * share_s[i];
        ++cell.samples;
      }
      if (cell.samples == 0) continue;
      cell.mean = sum / cell.samples;
      const double mse = sum2 / cell.samples;
      cell.rms = std::sqrt(mse);
      cell.spread = std::sqrt(sum_model / cell.samples);
      cell.spread_share = sum_share / cell.samples;
      // the mean square in units of the sensor noise the residual would have if the piles agreed
      const double mse_w = sum2w / cell.samples;
      // the samples the cell holds under the null, and the allowance they leave (header comment)
      const double n = cell.samples;
      const double correlated = (sum_share_v2 * (std::clamp(tau_v, 1.0, n) - 1.0) +
                                 sum_share_s2 * (std::clamp(tau_s, 1.0, n) - 1.0)) /
                                n;
      cell.null_samples = n / (1.0 + correlated);
      cell.allowance = correlated > 0.0
                           ? kNoiseAllowance * std::max(1.0, noise_quantile(cell.null_samples) /
                                                                 noise_quantile(n))
                           : kNoiseAllowance;
      cell.excess = std::log(std::max(mse_w / (cell.allowance * sigma[c] * sigma[c]), 1.0));
      out.excess += cell.excess;
      // the Gaussian log-likelihood's cell term, weighted by the cell's share of the channel's
      // samples (a short phase counts for its length), with its log-determinant (0 without a
      // spread); the smallest ratio counted: a residual a thousandth of the noise is as good as
      // none
      constexpr double kSmallestRatio = 1e-6;
      cell.log_ratio = std::log(std::max(mse_w / (sigma[c] * sigma[c]), kSmallestRatio)) +
                       sum_log_w / cell.samples;
      out.log_ratio += double(cell.samples) / double(tm.size()) * cell.log_ratio;
      cell.effective_samples = cell.samples / integrated_autocorrelation_time(z);
      out.cells.push_back(cell);
    }
  }
  return out;
}

double integrated_autocorrelation_time(const std::vector<double>& z,
                                       const std::vector<int>& segment) {
  const std::size_t n = z.size();
  if (!segment.empty() && segment.size() != n)
    throw Error("integrated_autocorrelation_time: " + std::to_string(segment.size()) +
                " segment labels for " + std::to_string(n) + " samples");
  double square = 0.0;
  for (const double v : z) square += v * v;
  if (n < 2 || !(square > 0.0)) return 1.0;
  // ρ_k, the uncentred autocorrelation at lag k over pairs within one segment
  const auto rho = [&](std::size_t k) {
    if (k == 0) return 1.0;
    double lag = 0.0;
    for (std::size_t i = 0; i + k < n; ++i)
      if (segment.empty() || segment[i] == segment[i + k]) lag += z[i] * z[i + k];
    return lag / square;
  };
  // τ = −1 + 2 Σ Γ_m, Γ_m = ρ_2m + ρ_2m+1, over the initial positive and non-increasing run
  double tau = -1.0, previous = HUGE_VAL;
  for (std::size_t m = 0; 2 * m + 1 < n; ++m) {
    const double pair = std::min(rho(2 * m) + rho(2 * m + 1), previous);
    if (!(pair > 0.0)) break;
    tau += 2.0 * pair;
    previous = pair;
  }
  return std::clamp(tau, 1.0, static_cast<double>(n));
}

double Residuals::excess_of(const std::vector<std::size_t>& channels) const {
  double sum = 0.0;
  for (const auto& cell : cells)
    if (std::find(channels.begin(), channels.end(), cell.channel) != channels.end()) sum += cell.excess;
  return sum;
}

double Residuals::spread_share_of(std::size_t channel) const {
  double share = 0.0;
  int samples = 0;
  for (const auto& cell : cells)
    if (cell.channel == channel) {
      share += cell.spread_share * cell.samples;
      samples += cell.samples;
    }
  return samples > 0 ? share / samples : 0.0;
}

Correlate strongest_correlate(const std::vector<double>& residual, const Run& measured) {
  const TimeSeries& m = measured.series;
  const auto& t = m[Channel::t];
  // the channels, then quantities derived from them
  std::vector<std::pair<std::string, std::vector<double>>> quantities;
  for (size_t c = 1; c < kChannelCount; ++c) quantities.emplace_back(kChannelNames[c], m.columns[c]);
  const auto lift_rate = derivative(t, m[Channel::d_lift]);
  const auto tilt_rate = derivative(t, m[Channel::d_tilt]);
  const auto acceleration = derivative(t, m[Channel::v_drive]);
  std::vector<double> hydraulic(t.size()), speed(t.size());
  for (size_t i = 0; i < t.size(); ++i) {
    hydraulic[i] = m[Channel::f_lift][i] * lift_rate[i] + m[Channel::f_tilt][i] * tilt_rate[i];
    speed[i] = std::abs(m[Channel::v_drive][i]);
  }
  quantities.emplace_back("lift_rate", lift_rate);
  quantities.emplace_back("tilt_rate", tilt_rate);
  quantities.emplace_back("drive_acceleration", acceleration);
  quantities.emplace_back("hydraulic_power", hydraulic);
  quantities.emplace_back("drive_speed_magnitude", speed);
  quantities.emplace_back("time", t);
  Correlate best;
  for (const auto& [name, q] : quantities) {
    const double r = pearson(residual, q);
    if (std::abs(r) > std::abs(best.r)) best = {name, r};
  }
  return best;
}

}  // namespace talus::sim2real
