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

// the longest scenario [s]: an hour of simulated time, far beyond a loading cycle (10-30 s) or the
// reliability soak (600 s), and short enough that no step count can overflow. Measured runs
// (sim2real/measured) are held to it too: their time column is the replay's duration
inline constexpr double kMaxScenarioDuration = 3600.0;
// the farthest a pile's toe may lie from the machine's start (x = 0) [m]: a loader approaches a
// pile over a few metres, and at 100 m a run of an hour at its top speed (about 10 m/s) still
// fits; far beyond, the device's float positions lose the millimetres a contact needs (their
// spacing is 1e-3 m at 1e4 m from the origin). Scenarios and measured runs alike
inline constexpr double kMaxPileToeX = 100.0;

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
