#include "sim2real/synthetic.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <random>
#include <sstream>

#include "host/error.hpp"

namespace talus::sim2real {

namespace {

Series2 points(const vehicle::PiecewiseLinear& f) {
  Series2 out;
  for (const auto& p : f.points()) out.push_back(p);
  return out;
}

}  // namespace

const std::map<std::string, double>& default_sensor_noise() {
  static const std::map<std::string, double> sigma = {
      {"f_lift", 5e3},    {"f_tilt", 3e3},     {"f_traction", 2e3},    {"v_drive", 0.02},
      {"d_lift", 1e-3},   {"d_tilt", 1e-3},    {"boom_deg", 0.2},      {"bucket_deg", 0.2},
      {"pitch_deg", 0.1}, {"x_vehicle", 0.02}, {"bucket_tip_x", 0.02}, {"bucket_tip_z", 0.02},
      {"power", 1e3}};
  return sigma;
}

std::map<std::string, double> parse_sensor_noise(const std::string& spec, const std::string& what) {
  std::map<std::string, double> sigma;
  std::stringstream in(spec);
  std::string part;
  while (std::getline(in, part, ',')) {
    // the keywords
    if (part == "none") continue;
    if (part == "default") {
      for (const auto& [k, v] : default_sensor_noise()) sigma[k] = v;
      continue;
    }
    // CHANNEL=SIGMA with a channel of the contract other than t
    const auto eq = part.find('=');
    const std::string channel = part.substr(0, eq);
    bool known = false;
    for (size_t c = 1; c < kChannelCount; ++c) known = known || channel == kChannelNames[c];
    if (eq == std::string::npos || !known)
      throw InputError(what + ": '" + part + "' is not none, default or CHANNEL=SIGMA with a channel of the "
                       "contract (f_lift, f_tilt, f_traction, v_drive, d_lift, ...)");
    // the whole text a number in SI units: "5kN" was read as 5 N
    const std::string text = part.substr(eq + 1);
    const std::optional<double> number = finite_number_in(text);
    if (!number)
      throw InputError(what + ": '" + part + "': the standard deviation '" + text +
                       "' is not a finite number in SI units (N, m, m/s, deg, W: 5 kN is 5000)");
    const double value = *number;
    // at most kMaxNoiseOverDefault times a real sensor's noise: beyond it the noise is the channel
    const double most = kMaxNoiseOverDefault * default_sensor_noise().at(channel);
    if (!(value >= 0.0 && value <= most))
      throw InputError(what + ": '" + part + "': the standard deviation must lie in 0-" +
                       message_number(most) + " (at most " + message_number(kMaxNoiseOverDefault) +
                       " times the default's " +
                       message_number(default_sensor_noise().at(channel)) + ")");
    sigma[channel] = value;
  }
  return sigma;
}

void add_sensor_noise(TimeSeries& series, const std::map<std::string, double>& sigma, unsigned seed) {
  std::mt19937_64 rng(seed);
  for (size_t c = 1; c < kChannelCount; ++c) {
    const auto it = sigma.find(kChannelNames[c]);
    if (it == sigma.end() || it->second == 0.0) continue;
    std::normal_distribution<double> noise(0.0, it->second);
    for (double& x : series.columns[c]) x += noise(rng);
  }
}

vehicle::Scenario varied_inputs(vehicle::Scenario sc, double v, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::array<double, 3> shifts{};  // drive, lift, tilt [s]
  std::size_t which = 0;
  for (vehicle::PiecewiseLinear* series : {&sc.drive, &sc.lift, &sc.tilt}) {
    auto points = series->points();
    const double scale = 1.0 + v * u(rng);
    double shift = v * u(rng) * kTimingShiftPerVariation;
    if (points.size() > 2) {
      // the inner points move together, at most halfway to the fixed first and last
      const double first = points[1].first, last = points[points.size() - 2].first;
      const double lo = -0.5 * std::max(0.0, first - points.front().first);
      const double hi = 0.5 * std::max(0.0, std::min(sc.duration, points.back().first) - last);
      shift = std::clamp(shift, lo, hi);
    }
    for (size_t i = 0; i < points.size(); ++i) {
      points[i].second *= scale;
      if (i > 0 && i + 1 < points.size()) points[i].first += shift;
    }
    *series = vehicle::PiecewiseLinear(points);
    shifts[which++] = points.size() > 2 ? shift : 0.0;
  }
  // the digging phase moves with the commands that make it: it starts when the drive brings the
  // bucket into the pile and ends with the boom's and the bucket's motion; kept inside the run
  // and in order (a scenario without marks has none to move)
  if (sc.dig_end > sc.dig_start) {
    const double start = std::clamp(sc.dig_start + shifts[0], 0.0, sc.duration);
    const double end = std::clamp(sc.dig_end + 0.5 * (shifts[1] + shifts[2]), 0.0, sc.duration);
    if (end > start) {
      sc.dig_start = start;
      sc.dig_end = end;
    }
  }
  return sc;
}

MeasuredMetadata synthetic_metadata(const vehicle::Scenario& scenario, const Series2& pile_scan,
                                    const RunSummary& summary) {
  MeasuredMetadata meta;
  meta.scenario = scenario.name;
  meta.machine = scenario.machine;
  meta.sample_rate_hz = kContractRateHz;
  meta.pile_toe_x_m = scenario.pile_toe_x;
  meta.pile_scan = pile_scan;
  meta.drive = points(scenario.drive);
  meta.lift = points(scenario.lift);
  meta.tilt = points(scenario.tilt);
  meta.loaded_mass_kg = summary.loaded_mass_kg;
  meta.work_J = summary.work_J;
  return meta;
}

}  // namespace talus::sim2real
