#include "sim2real/discovery.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "host/error.hpp"
#include "sim2real/residuals.hpp"
#include "vehicle/effect.hpp"
#include "vehicle/scenario.hpp"

namespace talus::sim2real {

namespace {

using vehicle::CorrectionInputs;
using vehicle::CorrectionKind;

// a two-sided 95 % interval of a normal estimate
constexpr double kZ95 = 1.959964;
// ridge added to the normal equations of RMS-scaled features, relative to their mean diagonal
// (1 per sample): keeps exactly collinear features (constant columns) solvable without changing a
// well-posed fit beyond rounding
constexpr double kRidge = 1e-10;
// a held-out error below this share of the residual's own mean square is an exact fit
constexpr double kExactFit = 1e-12;

std::size_t channel_column(const std::string& name) {
  for (std::size_t c = 1; c < kChannelCount; ++c)
    if (name == kChannelNames[c]) return c;
  throw Error("discovery: no channel '" + name + "'");
}

// the central difference of f over ±kRateHalfWindow samples around row j
double central_rate(const std::vector<double>& t, const std::vector<double>& f, std::size_t j) {
  return (f[j + kRateHalfWindow] - f[j - kRateHalfWindow]) /
         (t[j + kRateHalfWindow] - t[j - kRateHalfWindow]);
}

// f at time s, linear, the first value before the first time (as a delay line at rest)
double value_at(const std::vector<double>& t, const std::vector<double>& f, double s) {
  if (s <= t.front()) return f.front();
  if (s >= t.back()) return f.back();
  const std::size_t i =
      static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), s) - t.begin());
  const double w = (s - t[i - 1]) / (t[i] - t[i - 1]);
  return f[i - 1] + w * (f[i] - f[i - 1]);
}

std::string format(double v, int digits = 3) {
  char text[40];
  std::snprintf(text, sizeof text, "%.*g", digits, v);
  return text;
}

// Pearson's correlation of two columns; 0 when either is constant
double correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::VectorXd da = a.array() - a.mean(), db = b.array() - b.mean();
  const double norm = da.norm() * db.norm();
  return norm > 0.0 ? da.dot(db) / norm : 0.0;
}

// least squares on the columns `support` of x (zero elsewhere), through the normal equations with a
// ridge relative to their mean diagonal
Eigen::VectorXd solve_on(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                         const std::vector<Eigen::Index>& support) {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(x.cols());
  if (support.empty()) return c;
  // on columns scaled to unit RMS, so the ridge is the same small share of every column's weight
  // (a force column's square is 1e10 times a constant's)
  Eigen::MatrixXd a = x(Eigen::all, support);
  Eigen::VectorXd scale(a.cols());
  for (Eigen::Index k = 0; k < a.cols(); ++k) {
    scale[k] = std::sqrt(a.col(k).squaredNorm() /
                         static_cast<double>(std::max<Eigen::Index>(1, a.rows())));
    if (!(scale[k] > 0.0)) scale[k] = 1.0;
    a.col(k) /= scale[k];
  }
  Eigen::MatrixXd normal = a.transpose() * a;
  normal.diagonal().array() +=
      kRidge * std::max(normal.diagonal().mean(), std::numeric_limits<double>::min());
  const Eigen::VectorXd b = normal.ldlt().solve(a.transpose() * y).cwiseQuotient(scale);
  for (std::size_t i = 0; i < support.size(); ++i) c[support[i]] = b[static_cast<Eigen::Index>(i)];
  return c;
}

// the residual sum of squares of least squares on `support`, from the Gram matrix g = XᵀX, b = Xᵀy
// and yy = yᵀy: yy − b_Sᵀ g_SS⁻¹ b_S
double rss_on(const Eigen::MatrixXd& g, const Eigen::VectorXd& b, double yy,
              const std::vector<Eigen::Index>& support) {
  if (support.empty()) return yy;
  Eigen::MatrixXd gs = g(support, support);
  gs.diagonal().array() +=
      kRidge * std::max(gs.diagonal().mean(), std::numeric_limits<double>::min());
  const Eigen::VectorXd bs = b(support);
  return yy - bs.dot(gs.ldlt().solve(bs));
}

// mean-square prediction error of the held-out blocks for models of 1 .. kMaxTerms terms (index
// m − 1), each block predicted by the path fitted on the others
std::vector<double> cross_validated_mse(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                        const std::vector<int>& fold) {
  std::vector<double> sse(kMaxTerms, 0.0);
  for (int k = 0; k < kFolds; ++k) {
    std::vector<Eigen::Index> train, test;
    for (Eigen::Index r = 0; r < x.rows(); ++r) (fold[r] == k ? test : train).push_back(r);
    if (test.empty()) continue;
    if (train.empty())
      return std::vector<double>(kMaxTerms, std::numeric_limits<double>::infinity());
    const Eigen::MatrixXd xt = x(train, Eigen::all);
    const Eigen::VectorXd yt = y(train);
    const auto path = elimination_path(xt, yt);
    for (int m = 1; m <= kMaxTerms; ++m) {
      // a model size this fold's path does not reach cannot be scored on it
      if (m >= static_cast<int>(path.size())) {
        sse[m - 1] = std::numeric_limits<double>::infinity();
        continue;
      }
      const Eigen::VectorXd c = solve_on(xt, yt, path[m]);
      sse[m - 1] += (y(test) - x(test, Eigen::all) * c).squaredNorm();
    }
  }
  for (double& v : sse) v /= static_cast<double>(std::max<Eigen::Index>(1, x.rows()));
  return sse;
}

}  // namespace

std::string DiscoveryTarget::label() const {
  switch (kind) {
    case CorrectionKind::actuator:
      return target + " speed";
    case CorrectionKind::traction:
      return "tractive force";
    case CorrectionKind::sensor:
      break;
  }
  return target + " reading";
}
std::string DiscoveryTarget::effect_name() const {
  switch (kind) {
    case CorrectionKind::actuator:
      return "learned_actuator_correction";
    case CorrectionKind::traction:
      return "learned_traction_correction";
    case CorrectionKind::sensor:
      break;
  }
  return "learned_sensor_correction";
}
std::string DiscoveryTarget::option() const {
  switch (kind) {
    case CorrectionKind::actuator:
      return "actuator=" + target;
    case CorrectionKind::traction:
      return "";  // one drive, nothing to choose
    case CorrectionKind::sensor:
      break;
  }
  return "channel=" + target;
}

std::vector<DiscoveryTarget> discovery_targets(const std::vector<std::string>& sensor_channels) {
  std::vector<DiscoveryTarget> out;
  for (const char* a : {"drive", "lift", "tilt"}) out.push_back({CorrectionKind::actuator, a});
  out.push_back({CorrectionKind::traction, "traction"});
  for (const auto& c : sensor_channels) {
    channel_column(c);  // a known channel
    out.push_back({CorrectionKind::sensor, c});
  }
  return out;
}

double command_limit(const DiscoveryTarget& target, const vehicle::MachineDescription& machine) {
  if (target.kind != CorrectionKind::actuator) return std::numeric_limits<double>::infinity();
  if (target.target == "drive") return machine.driveline.top_speed;
  for (const auto& c : machine.cylinders)
    if (c.role == target.target) return c.max_speed;
  throw InputError(machine.source + ": no " + target.target + " cylinder, so no " + target.label() +
                   " to correct");
}

RegressionData regression_data(const DiscoveryTarget& target,
                               const std::vector<const MeasuredRun*>& measured,
                               const std::vector<const Run*>& simulated, double limit) {
  if (measured.size() != simulated.size())
    throw Error("discovery: measured and simulated runs differ in number");
  const auto& features = vehicle::correction_features(target.kind);
  std::vector<std::vector<double>> rows;
  std::vector<double> ys;
  RegressionData data;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    const TimeSeries& m = measured[i]->run.series;
    const std::vector<double>& t = m[Channel::t];
    // the simulation at the measured times (InputError when it does not cover them)
    const TimeSeries s = resample(simulated[i]->series, t);
    const std::size_t n = t.size();
    if (n < 2 * kRateHalfWindow + 2) continue;
    const double t0 = t.front(), span = t.back() - t.front();
    const MeasuredMetadata& meta = measured[i]->meta;
    const Series2& inputs = target.target == "drive"  ? meta.drive
                            : target.target == "lift" ? meta.lift
                                                      : meta.tilt;
    const vehicle::PiecewiseLinear command(
        target.kind == CorrectionKind::actuator ? inputs : Series2{{0.0, 0.0}});
    // an actuator's force (the traction's: the load, f_lift) and the power through the lag the
    // correction reads them with
    const Channel force_channel = target.kind == CorrectionKind::traction ? Channel::f_lift
                                  : target.target == "drive"              ? Channel::f_traction
                                  : target.target == "lift"               ? Channel::f_lift
                                                                          : Channel::f_tilt;
    std::vector<double> force = m[force_channel], power = m[Channel::power];
    // the stroke a feature reads: the cylinder's own (the drive's and the traction's: the boom's),
    // as measured for an actuator and the traction and as simulated for a sensor; the digging phase
    // from the simulated run's marks, the phase its effects saw (the replay takes the measured
    // run's marks where it has them)
    const std::vector<double>& stroke = target.kind == CorrectionKind::sensor ? s[Channel::d_lift]
                                        : target.target == "tilt"             ? m[Channel::d_tilt]
                                                                              : m[Channel::d_lift];
    const RunSummary& marks = simulated[i]->summary;
    const auto digging = [&](double when) {
      return marks.dig_start_s && marks.dig_end_s &&
                     vehicle::in_dig_phase(when, *marks.dig_start_s, *marks.dig_end_s)
                 ? 1.0
                 : 0.0;
    };
    for (std::size_t j = 1; j < n; ++j) {
      force[j] = vehicle::lag_step(force[j - 1], m[force_channel][j], t[j] - t[j - 1]);
      power[j] = vehicle::lag_step(power[j - 1], m[Channel::power][j], t[j] - t[j - 1]);
    }
    // every sample's features, and for an actuator what its speed limit takes off the command
    // (the baseline's speed is clip(u), the correction's target u + Δu)
    std::vector<std::vector<double>> phi(n, std::vector<double>(features.size()));
    std::vector<double> clipped(n, 0.0);
    for (std::size_t j = 0; j < n; ++j) {
      CorrectionInputs in;
      in.stroke = stroke[j];
      in.digging = digging(t[j]);
      if (target.kind == CorrectionKind::actuator) {
        // the command from the operator's inputs; the state as measured
        in.a = command(t[j]);
        for (std::size_t d = 0; d < vehicle::kCorrectionDelays.size(); ++d)
          in.a_delayed[d] = command(
              std::max(t[j] - vehicle::kCorrectionDelays[d], command.points().front().first));
        in.force = force[j];
        in.power = power[j];
        clipped[j] = std::clamp(in.a, -limit, limit) - in.a;
      } else if (target.kind == CorrectionKind::traction) {
        // the drive's speed and the load as measured
        const std::vector<double>& v = m[Channel::v_drive];
        in.a = v[j];
        for (std::size_t d = 0; d < vehicle::kCorrectionDelays.size(); ++d)
          in.a_delayed[d] = value_at(t, v, t[j] - vehicle::kCorrectionDelays[d]);
        in.force = force[j];
        in.power = power[j];
      } else {
        // the simulated reading stands for the truth the sensor distorts
        const std::vector<double>& truth = s.columns[channel_column(target.target)];
        in.a = truth[j];
        in.rate = (truth[j] - value_at(t, truth, t[j] - vehicle::kRateSpan)) / vehicle::kRateSpan;
        in.force = s[Channel::f_lift][j];
        in.power = s[Channel::power][j];
        for (std::size_t d = 0; d < vehicle::kCorrectionDelays.size(); ++d)
          in.a_delayed[d] = value_at(t, truth, t[j] - vehicle::kCorrectionDelays[d]);
      }
      for (std::size_t k = 0; k < features.size(); ++k) phi[j][k] = features[k].value(in);
    }
    // a cylinder's residual is a central difference of strokes, the mean of its speed over the
    // window: its features are the same window's means (trapezoidal), so a correction that jumps
    // as the command crosses zero is fitted to the ramp the difference makes of it, not to a jump
    // the data cannot show (until 2026-11-28 the features were taken at the window's centre, and a
    // lift dead band δ sign(u) was fitted as a polynomial in u, whose smooth onset matched that
    // ramp better). The drive's speed and a sensor's reading are samples: their features too
    const bool windowed = target.kind == CorrectionKind::actuator && target.target != "drive";
    const auto window_mean = [&](std::size_t j, const auto& value) {
      if (!windowed) return value(j);
      double sum = 0.0;
      for (std::size_t i = j - kRateHalfWindow; i < j + kRateHalfWindow; ++i)
        sum += 0.5 * (t[i + 1] - t[i]) * (value(i) + value(i + 1));
      return sum / (t[j + kRateHalfWindow] - t[j - kRateHalfWindow]);
    };
    for (std::size_t j = kRateHalfWindow; j + kRateHalfWindow < n; ++j) {
      double y = 0.0;
      if (target.kind == CorrectionKind::actuator) {
        if (target.target == "drive") {
          y = m[Channel::v_drive][j] - s[Channel::v_drive][j];
        } else {
          const Channel stroke = target.target == "lift" ? Channel::d_lift : Channel::d_tilt;
          y = central_rate(t, m[stroke], j) - central_rate(t, s[stroke], j);
        }
        // on the command's scale
        y += window_mean(j, [&](std::size_t i) { return clipped[i]; });
      } else if (target.kind == CorrectionKind::traction) {
        y = m[Channel::f_traction][j] - s[Channel::f_traction][j];
      } else {
        y = m.columns[channel_column(target.target)][j] -
            s.columns[channel_column(target.target)][j];
      }
      std::vector<double> row(features.size());
      for (std::size_t k = 0; k < features.size(); ++k)
        row[k] = window_mean(j, [&](std::size_t i) { return phi[i][k]; });
      rows.push_back(std::move(row));
      ys.push_back(y);
      data.fold.push_back(std::min(kFolds - 1, static_cast<int>(kFolds * (t[j] - t0) / span)));
      data.run.push_back(static_cast<int>(i));
    }
  }
  data.features.resize(static_cast<Eigen::Index>(rows.size()),
                       static_cast<Eigen::Index>(features.size()));
  data.residual.resize(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (std::size_t k = 0; k < features.size(); ++k) data.features(r, k) = rows[r][k];
    data.residual[r] = ys[r];
  }
  return data;
}

namespace {

// the normal equations of the features scaled to unit RMS (so the ridge treats them alike), and
// the features that are not zero throughout (the others stay out of every model)
struct ScaledGram {
  Eigen::MatrixXd g;
  Eigen::VectorXd b;
  double yy = 0.0;
  std::vector<Eigen::Index> usable;
};
ScaledGram scaled_gram(const Eigen::MatrixXd& x, const Eigen::VectorXd& y) {
  ScaledGram out;
  Eigen::VectorXd scale(x.cols());
  for (Eigen::Index k = 0; k < x.cols(); ++k) {
    scale[k] = std::sqrt(x.col(k).squaredNorm() /
                         static_cast<double>(std::max<Eigen::Index>(1, x.rows())));
    if (scale[k] > 0.0) out.usable.push_back(k);
    if (!(scale[k] > 0.0)) scale[k] = 1.0;
  }
  const Eigen::MatrixXd z = x * scale.cwiseInverse().asDiagonal();
  out.g = z.transpose() * z;
  out.b = z.transpose() * y;
  out.yy = y.squaredNorm();
  return out;
}

// a support of fixed size improved one exchange at a time: while replacing one of its terms by a
// feature outside it lowers the residual, the best such exchange is made. Backward elimination
// can drop the right term early, while a group of nearly equal features (sign(u) and the dead
// bands clip(u, ±δ₀) under commands held beyond δ₀) shares its weight, and end on a member that
// fits worse (measured: a sign(u) truth kept as clip(u, ±0.02 m/s), which widened its delay
// term's interval to 17 % of its value); the exchange restores the one that fits best
void exchange_terms(const ScaledGram& gram, std::vector<Eigen::Index>& support) {
  double best = rss_on(gram.g, gram.b, gram.yy, support);
  // each exchange lowers the residual, so none repeats; the bound only guards against rounding
  for (std::size_t round = 0; round < gram.usable.size() * support.size(); ++round) {
    std::size_t at = 0;
    Eigen::Index with = -1;
    double least = best;
    for (std::size_t i = 0; i < support.size(); ++i)
      for (Eigen::Index j : gram.usable) {
        if (std::find(support.begin(), support.end(), j) != support.end()) continue;
        std::vector<Eigen::Index> trial = support;
        trial[i] = j;
        const double rss = rss_on(gram.g, gram.b, gram.yy, trial);
        // a gain beyond rounding (a relative 1e-12 of the residual)
        if (rss < least - 1e-12 * best) {
          least = rss;
          at = i;
          with = j;
        }
      }
    if (with < 0) break;
    support[at] = with;
    best = least;
  }
  std::sort(support.begin(), support.end());
}

// the backward-elimination path (elimination_path) from the normal equations
std::vector<std::vector<Eigen::Index>> path_of(const ScaledGram& gram) {
  const Eigen::MatrixXd& g = gram.g;
  const Eigen::VectorXd& b = gram.b;
  const double yy = gram.yy;
  std::vector<Eigen::Index> support = gram.usable;
  // drop, one at a time, the term whose loss raises the residual least
  std::vector<std::vector<Eigen::Index>> path(support.size() + 1);
  path[support.size()] = support;
  while (!support.empty()) {
    std::size_t weakest = 0;
    double least = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < support.size(); ++i) {
      std::vector<Eigen::Index> without = support;
      without.erase(without.begin() + static_cast<std::ptrdiff_t>(i));
      const double rss = rss_on(g, b, yy, without);
      if (rss < least) {
        least = rss;
        weakest = i;
      }
    }
    support.erase(support.begin() + static_cast<std::ptrdiff_t>(weakest));
    path[support.size()] = support;
  }
  return path;
}

}  // namespace

std::vector<std::vector<Eigen::Index>> elimination_path(const Eigen::MatrixXd& x,
                                                        const Eigen::VectorXd& y) {
  return path_of(scaled_gram(x, y));
}

DiscoveredCorrection fit_correction(const DiscoveryTarget& target, const RegressionData& data) {
  DiscoveredCorrection out;
  out.target = target;
  out.samples = static_cast<int>(data.residual.size());
  const Eigen::MatrixXd& x = data.features;
  const Eigen::VectorXd& y = data.residual;
  if (y.size() == 0) return out;
  out.cv_mse_none = y.squaredNorm() / y.size();
  if (!(out.cv_mse_none > 0.0)) return out;  // nothing to correct
  // the held-out error of 1 .. kMaxTerms terms; the fewest within kOneSeRule of the least
  const std::vector<double> cv = cross_validated_mse(x, y, data.fold);
  const double least = *std::min_element(cv.begin(), cv.end());
  int terms = 1;
  // (the floor: noise-free data leaves rounding alone, which no factor of the least tells apart)
  const double good_enough = std::max(kOneSeRule * least, kExactFit * out.cv_mse_none);
  while (terms < kMaxTerms && cv[terms - 1] > good_enough) ++terms;
  out.cv_mse = cv[terms - 1];
  if (!(out.cv_mse <= (1.0 - kMinRegressionGain) * out.cv_mse_none)) return out;

  // ordinary least squares on the support, with 95 % intervals inflated for autocorrelation; a
  // term whose interval holds zero is dropped (the least significant first) and the rest refitted
  const ScaledGram gram = scaled_gram(x, y);
  const auto path = path_of(gram);
  if (static_cast<std::size_t>(terms) >= path.size()) return out;
  std::vector<Eigen::Index> support = path[terms];
  exchange_terms(gram, support);
  Eigen::VectorXd c, half;
  while (!support.empty()) {
    const Eigen::MatrixXd a = x(Eigen::all, support);
    c = solve_on(x, y, support)(support);
    const Eigen::VectorXd r = y - a * c;
    const double var = r.squaredNorm();
    const double dof =
        std::max<double>(1.0, static_cast<double>(r.size()) - static_cast<double>(support.size()));
    const double sigma2 = var / dof *
                          integrated_autocorrelation_time(
                              std::vector<double>(r.data(), r.data() + r.size()), data.run);
    const Eigen::MatrixXd cov = sigma2 * (a.transpose() * a).inverse();
    half = kZ95 * cov.diagonal().cwiseMax(0.0).cwiseSqrt();
    Eigen::Index weakest = 0;
    const double significance = (c.cwiseAbs().cwiseQuotient(half)).minCoeff(&weakest);
    if (significance >= 1.0) break;
    support.erase(support.begin() + weakest);
  }
  if (support.empty()) return out;

  const auto& features = vehicle::correction_features(target.kind);
  const vehicle::CorrectionSymbols symbols =
      vehicle::correction_symbols(target.kind, target.target);
  for (std::size_t i = 0; i < support.size(); ++i) {
    const auto& f = features[support[i]];
    DiscoveredTerm term;
    term.feature = f.name;
    term.expression = vehicle::correction_expression(f, symbols);
    const std::string feature_unit = vehicle::correction_unit(f, symbols);
    term.unit = feature_unit == "1" ? symbols.corrected_unit
                                    : "(" + symbols.corrected_unit + ")/(" + feature_unit + ")";
    term.coefficient = c[static_cast<Eigen::Index>(i)];
    term.half_width = half[static_cast<Eigen::Index>(i)];
    // the features these data cannot tell from it
    for (Eigen::Index j = 0; j < x.cols(); ++j) {
      if (std::find(support.begin(), support.end(), j) != support.end()) continue;
      if (std::abs(correlation(x.col(support[i]), x.col(j))) >= kAliasCorrelation) {
        term.aliases.emplace_back(features[j].name);
        term.alias_expressions.push_back(vehicle::correction_expression(features[j], symbols));
      }
    }
    out.terms.push_back(term);
  }
  describe_correction(out);
  return out;
}

void describe_correction(DiscoveredCorrection& c) {
  const vehicle::CorrectionSymbols symbols =
      vehicle::correction_symbols(c.target.kind, c.target.target);
  c.spec = c.target.effect_name() + ":" + c.target.option();
  c.expression = "Δ" + symbols.corrected + " [" + symbols.corrected_unit + "] =";
  for (std::size_t i = 0; i < c.terms.size(); ++i) {
    const DiscoveredTerm& term = c.terms[i];
    char value[40];
    std::snprintf(value, sizeof value, "%.17g", term.coefficient);
    c.spec += (c.spec.back() == ':' ? "" : ",") + term.feature + "=" + value;
    c.expression += (i == 0 ? " " : " + ") + format(term.coefficient) + " (±" +
                    format(term.half_width, 2) + ") " + term.unit +
                    (term.feature == "one" ? "" : " · " + term.expression);
    // what the data cannot tell it from, said beside it
    for (std::size_t k = 0; k < term.alias_expressions.size(); ++k)
      c.expression += (k == 0 ? " [on these runs ≡ " : ", ") + term.alias_expressions[k] +
                      (k + 1 == term.alias_expressions.size() ? "]" : "");
  }
}

nlohmann::json correction_json(const DiscoveredCorrection& c) {
  nlohmann::json terms = nlohmann::json::array();
  for (const auto& t : c.terms)
    terms.push_back({{"feature", t.feature},
                     {"expression", t.expression},
                     {"unit", t.unit},
                     {"coefficient", t.coefficient},
                     {"ci95", {t.coefficient - t.half_width, t.coefficient + t.half_width}},
                     {"aliases", t.aliases}});
  nlohmann::json dictionary = nlohmann::json::array();
  const vehicle::CorrectionSymbols symbols =
      vehicle::correction_symbols(c.target.kind, c.target.target);
  for (const auto& f : vehicle::correction_features(c.target.kind))
    dictionary.push_back(
        {{"feature", f.name}, {"expression", vehicle::correction_expression(f, symbols)}});
  nlohmann::json j = {
      {"target", c.target.label()}, {"effect", c.spec},       {"expression", c.expression},
      {"coefficients", terms},      {"features", dictionary}, {"terms", c.terms.size()},
      {"samples", c.samples},       {"cv_mse", c.cv_mse},     {"cv_mse_none", c.cv_mse_none},
      {"simulated", c.simulated},   {"refined", c.refined}};
  if (c.simulated) {
    j["excess_calibration"] = c.excess_calibration;
    j["excess_validation"] = c.excess_validation;
    j["held_out_error_cut"] = c.explained;
    j["explained_on"] = c.explained_on;
    j["channels"] = c.channels;
  }
  return j;
}

}  // namespace talus::sim2real
