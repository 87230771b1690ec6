#include "vehicle/scenario.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "host/data_files.hpp"
#include "host/error.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/machine.hpp"

namespace talus::vehicle {

PiecewiseLinear::PiecewiseLinear(std::vector<std::pair<double, double>> points) : points_(std::move(points)) {}

double PiecewiseLinear::operator()(double t) const {
  if (points_.empty()) return 0.0;
  if (t <= points_.front().first) return points_.front().second;
  if (t >= points_.back().first) return points_.back().second;
  const auto it = std::upper_bound(points_.begin(), points_.end(), t,
                                   [](double x, const std::pair<double, double>& p) { return x < p.first; });
  const auto& [t1, v1] = *it;
  const auto& [t0, v0] = *(it - 1);
  return t1 > t0 ? v0 + (v1 - v0) * (t - t0) / (t1 - t0) : v1;
}

namespace {

// the shortest [s]: two samples of the 100 Hz sensors
constexpr double kMinDuration = 0.02;

// an operator's target speeds [[t, v], ...]: finite, in time order, |v| at most `fastest` [m/s]
// (a lever at its stop asks the machine's top speed; 1e30 m/s ran as a valid scenario)
PiecewiseLinear series(const DataFile& f, const std::string& key, double fastest) {
  const auto& j = f.member(f.root(), "", key);
  if (!j.is_array() || j.empty()) f.fail(key, "is not a non-empty array", "give [[t, v], ...] with t in s and v in m/s");
  std::vector<std::pair<double, double>> pts;
  for (size_t i = 0; i < j.size(); ++i) {
    const std::string where = key + "[" + std::to_string(i) + "]";
    const auto& p = j[i];
    if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number() ||
        !std::isfinite(p[0].get<double>()) || !std::isfinite(p[1].get<double>())) {
      f.fail(where, "is not a pair of finite numbers", "write [t, v]");
    }
    if (!(std::abs(p[1].get<double>()) <= fastest))
      f.fail(where, "asks " + message_number(p[1].get<double>()) + " m/s",
             "give a target speed within +-" + message_number(fastest) +
                 " m/s (no loader drives or moves a cylinder faster)");
    if (!pts.empty() && p[0].get<double>() < pts.back().first) {
      f.fail(where, "goes back in time", "sort the points by time");
    }
    pts.emplace_back(p[0].get<double>(), p[1].get<double>());
  }
  return PiecewiseLinear(std::move(pts));
}

}  // namespace

Scenario load_scenario(const std::string& name_or_path) {
  // a shipped name in any case (hd27, HD27: summaries and metadata spell it upper case) or a path
  std::string path = find_data_file(name_or_path, "scenarios");
  if (path.empty()) {
    std::string lower = name_or_path;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
    path = find_data_file(lower, "scenarios");
  }
  if (path.empty()) {
    std::string searched;
    for (const auto& root : data_search_paths()) searched += (searched.empty() ? "" : ", ") + root + "/scenarios";
    throw InputError("scenario '" + name_or_path + "': no such file, and no " + name_or_path + ".json in " + searched +
                     "; give a path or a shipped name (TALUS_DATA_DIR points at another data/ folder)");
  }
  const DataFile f(path);
  const auto& root = f.root();
  Scenario s;
  s.path = path;
  s.name = f.text(root, "", "name");
  s.description = root.contains("description") && root["description"].is_string() ? root["description"].get<std::string>() : "";
  s.pile = root.contains("pile") && root["pile"].is_boolean() && root["pile"].get<bool>();
  if (root.contains("pile") && !root["pile"].is_boolean()) f.fail("pile", "is not true or false", "write true or false");
  s.machine = f.text(root, "", "machine");
  s.duration = f.plain_number(root, "", "duration");
  s.payload = root.contains("payload") ? f.plain_number(root, "", "payload") : 0.0;
  if (!(s.duration > 0)) f.fail("duration", "is not > 0", "give the simulated time in s");
  if (s.duration > kMaxScenarioDuration)
    f.fail("duration", "is above " + std::to_string(static_cast<int>(kMaxScenarioDuration)) + " s",
           "give at most an hour of simulated time (a loading cycle lasts 10-30 s)");
  // the sensors sample every 10 ms: a run shorter than two samples has nothing to compare
  if (s.duration < kMinDuration)
    f.fail("duration", "is below 0.02 s (two sensor samples)", "give the simulated time in s");
  if (!(s.payload >= 0)) f.fail("payload", "is negative", "give the payload in kg (0 for an empty bucket)");
  if (s.pile) {
    // the pile, its placement and the digging phase; the timestep comes from the fidelity level.
    // The load is the gravel the bucket picks up: a payload on top would count it twice
    if (s.payload > 0) f.fail("payload", "is set for a scenario with a pile", "remove it (the bucket fills with particles)");
    s.pile_profile = root.contains("pile_profile") ? f.text(root, "", "pile_profile") : "default";
    s.pile_toe_x = f.plain_number(root, "", "pile_toe_x");
    if (!(s.pile_toe_x >= 0.0 && s.pile_toe_x <= kMaxPileToeX))
      f.fail("pile_toe_x",
             "lies outside 0-" + message_number(kMaxPileToeX) + " m from the machine's start",
             "give the pile's toe in m ahead of the machine (the shipped scenarios: 3.95-4.25 m)");
    s.dig_start = f.plain_number(root, "", "dig_start");
    s.dig_end = f.plain_number(root, "", "dig_end");
    if (!(s.dig_start >= 0 && s.dig_start < s.dig_end && s.dig_end <= s.duration))
      f.fail("dig_end", "does not make 0 <= dig_start < dig_end <= duration", "give the digging phase in s");
    if (root.contains("field")) {
      const auto& field = f.member(root, "", "field");
      s.field_loaded_mass_kg = f.plain_number(field, "field", "loaded_mass_kg");
      s.field_work_J = f.plain_number(field, "field", "work_J");
    }
  } else {
    s.timestep = f.plain_number(root, "", "timestep");
    // at least 1 ms (a 10 s scenario is then 10,000 steps; 1e-7 s ran for hours) and at most the
    // sensors' 10 ms period
    if (!(s.timestep >= 0.001 && s.timestep <= 0.01))
      f.fail("timestep", "is not in [0.001, 0.01] s", "use e.g. 0.005 (sensors run at 100 Hz)");
    const double per_sample = 0.01 / s.timestep;
    if (std::abs(per_sample - std::round(per_sample)) > 1e-9) {
      f.fail("timestep", "does not divide the 10 ms sensor period", "use 0.01, 0.005, 0.0025, 0.002 or 0.001");
    }
  }
  s.drive = series(f, "drive", kMaxDriveSpeed);
  s.lift = series(f, "lift", kMaxCylinderSpeed);
  s.tilt = series(f, "tilt", kMaxCylinderSpeed);
  return s;
}

std::string machine_file(const Scenario& scenario) {
  const std::string path = find_data_file(scenario.machine, "machines");
  if (path.empty())
    throw InputError(scenario.path + ": field 'machine' names '" + scenario.machine +
                     "', which is neither a file nor data/machines/" + scenario.machine + ".json; fix the name");
  return path;
}

}  // namespace talus::vehicle
