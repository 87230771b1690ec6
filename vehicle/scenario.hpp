// Feedforward scenarios (SPEC §3): target-speed time series for drive, lift and tilt, as
// piecewise-linear series in a JSON file (data/scenarios/*.json):
//   {"name": "...", "description": "...", "machine": "wa320", "pile": false,
//    "duration": 12.0, "timestep": 0.005, "payload": 3500,
//    "drive": [[t, v], ...], "lift": [[t, v], ...], "tilt": [[t, v], ...]}   (s, m/s, kg)
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
};

// by name (data/scenarios/NAME.json) or path; InputError naming file, field and fix
Scenario load_scenario(const std::string& name_or_path);

}  // namespace talus::vehicle
