// Feedforward scenarios (SPEC §3): target-speed time series for drive, lift and tilt, as
// piecewise-linear series in a JSON file (data/scenarios/*.json):
//   {"name": "...", "description": "...", "machine": "wa320", "pile": false,
//    "duration": 12.0, "timestep": 0.005, "payload": 3500,
//    "drive": [[t, v], ...], "lift": [[t, v], ...], "tilt": [[t, v], ...]}   (s, m/s, kg)
// Scenarios with "pile": true dig in a particle pile (digging/digging.hpp); their timestep comes
// from the fidelity level, and they add
//    "pile_profile": "default",   the pile's cross-section (data/piles/NAME.json or a path)
//    "pile_toe_x": 5.0,           world x of the profile's toe (the machine's front axle is at 0)
//    "dig_start": 1.0, "dig_end": 8.0,   the digging phase the metrics compare [s]
//    "field": {"loaded_mass_kg": 2700, "work_J": 127000}   the field test's values (optional)
#pragma once
#include <string>
#include <utility>
#include <vector>

namespace talus::vehicle {

// linear between points, constant before the first and after the last
class PiecewiseLinear {
 public:
  PiecewiseLinear() = default;
  explicit PiecewiseLinear(std::vector<std::pair<double, double>> points);
  double operator()(double t) const;
  const std::vector<std::pair<double, double>>& points() const { return points_; }

 private:
  std::vector<std::pair<double, double>> points_;
};

struct Scenario {
  std::string name, description, path;
  std::string machine;       // machine data file name or path
  bool pile = false;         // needs the particle pile
  double duration = 0.0;     // s
  double timestep = 0.005;   // s
  double payload = 0.0;      // kg
  PiecewiseLinear drive, lift, tilt;  // target speeds [m/s]
  // particle-pile scenarios
  std::string pile_profile;          // name or path of the pile profile
  double pile_toe_x = 0.0;           // [m]
  double dig_start = 0.0, dig_end = 0.0;  // digging phase [s]
  double field_loaded_mass_kg = 0.0, field_work_J = 0.0;  // 0 when not given
};

// by name (data/scenarios/NAME.json, any case) or path; InputError naming file, field and fix
Scenario load_scenario(const std::string& name_or_path);

// the path of the scenario's machine data file (data/machines/NAME.json or a path); InputError
// naming the scenario's field 'machine' when there is none
std::string machine_file(const Scenario& scenario);

}  // namespace talus::vehicle
