// Feedforward scenario files and the piecewise-linear target speeds.
#include "vehicle/scenario.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "host/error.hpp"

namespace talus::vehicle {
namespace {

TEST(ScenarioTest, PiecewiseLinearInterpolatesAndHolds) {
  const PiecewiseLinear f({{1.0, 0.0}, {2.0, 2.0}, {4.0, -2.0}});
  EXPECT_DOUBLE_EQ(f(0.0), 0.0);
  EXPECT_DOUBLE_EQ(f(1.5), 1.0);
  EXPECT_DOUBLE_EQ(f(3.0), 0.0);
  EXPECT_DOUBLE_EQ(f(9.0), -2.0);
}

TEST(ScenarioTest, ShippedFlatLiftLoads) {
  const Scenario s = load_scenario("flat-lift");
  EXPECT_EQ(s.name, "flat-lift");
  EXPECT_FALSE(s.pile);
  EXPECT_EQ(s.machine, "wa320");
  EXPECT_GT(s.duration, 0.0);
  EXPECT_GT(s.payload, 0.0);
  EXPECT_GT(s.drive(2.0), 0.0);  // it drives
  EXPECT_GT(s.lift(7.0), 0.0);   // and lifts
}

TEST(ScenarioTest, MalformedScenarioNamesFileAndField) {
  const auto path = (std::filesystem::temp_directory_path() / "talus_bad_scenario.json").string();
  std::ofstream(path) << R"({"name": "x", "machine": "wa320", "duration": 5, "timestep": 0.005,
                           "drive": [[0, 0], [1, "fast"]], "lift": [[0, 0]], "tilt": [[0, 0]]})";
  try {
    load_scenario(path);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(path), std::string::npos) << m;
    EXPECT_NE(m.find("drive[1]"), std::string::npos) << m;
  }
  std::ofstream(path) << R"({"name": "x", "machine": "wa320", "duration": 5, "timestep": 0.003,
                           "drive": [[0, 0]], "lift": [[0, 0]], "tilt": [[0, 0]]})";
  EXPECT_THROW(load_scenario(path), InputError);  // 3 ms does not divide the 10 ms sensor period
  // 1e-7 s divides it, but a 5 s scenario would be 50 million steps (it ran for hours)
  std::ofstream(path) << R"({"name": "x", "machine": "wa320", "duration": 5, "timestep": 1e-7,
                           "drive": [[0, 0]], "lift": [[0, 0]], "tilt": [[0, 0]]})";
  try {
    load_scenario(path);
    FAIL() << "1e-7 s: no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("field 'timestep' is not in [0.001, 0.01] s"),
              std::string::npos)
        << e.what();
  }
  // an operator's target speed beyond any loader's (1e30 m/s ran as a valid scenario, clamped)
  std::ofstream(path) << R"({"name": "x", "machine": "wa320", "duration": 5, "timestep": 0.005,
                           "drive": [[0, 0]], "lift": [[0, 0], [1, 1e30]], "tilt": [[0, 0]]})";
  try {
    load_scenario(path);
    FAIL() << "1e30 m/s: no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("field 'lift[1]' asks 1e+30 m/s"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(load_scenario("no-such-scenario"), InputError);
}

// a duration outside [0.02 s, 3600 s] is refused naming the field: 1e9 s overflowed the step
// count (one sample, a negative real-time factor, exit 0), and a run shorter than two sensor
// samples wrote a series nothing could compare
TEST(ScenarioTest, DurationOutsideItsRangeNamesTheField) {
  const auto path =
      (std::filesystem::temp_directory_path() / "talus_duration_scenario.json").string();
  for (const char* duration : {"1e9", "3601", "0.001"}) {
    std::ofstream(path) << R"({"name": "x", "machine": "wa320", "timestep": 0.005, "duration": )"
                        << duration
                        << R"(, "drive": [[0, 0]], "lift": [[0, 0]], "tilt": [[0, 0]]})";
    try {
      load_scenario(path);
      FAIL() << duration << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("field 'duration'"), std::string::npos) << e.what();
    }
  }
  std::ofstream(path) << R"({"name": "x", "machine": "wa320", "timestep": 0.005, "duration": 600,
                           "drive": [[0, 0]], "lift": [[0, 0]], "tilt": [[0, 0]]})";
  EXPECT_NO_THROW(load_scenario(path));  // the soak's ten minutes
}

// a pile's toe more than 100 m from the machine's start is refused naming the field: at 1e12 m
// the run ended with a misleading "needs more than 64 colours" from the device's float positions
TEST(ScenarioTest, PileToeFarAwayNamesTheField) {
  const auto path = (std::filesystem::temp_directory_path() / "talus_toe_scenario.json").string();
  for (const char* toe : {"1e12", "101", "-1"}) {
    std::ofstream(path)
        << R"({"name": "x", "machine": "wa320", "duration": 9, "pile": true, "pile_toe_x": )" << toe
        << R"(, "dig_start": 1, "dig_end": 8, "drive": [[0, 0]], "lift": [[0, 0]], "tilt": [[0, 0]]})";
    try {
      load_scenario(path);
      FAIL() << toe << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("field 'pile_toe_x'"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace talus::vehicle
