// sim2real/synthetic: the noise model and the operator's variation of field-like data
#include "sim2real/synthetic.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>

#include "host/error.hpp"
#include "tests/sim2real/synthetic_runs.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/scenario.hpp"
#include "vehicle/sensors.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus::sim2real {
namespace {

// "default" is the documented table, a pair changes one entry, "none" adds nothing; a bad part
// is named with where it came from
TEST(Synthetic, NoiseSpecsParseAndBadPartsAreNamed) {
  EXPECT_TRUE(parse_sensor_noise("none", "--noise").empty());
  const auto d = parse_sensor_noise("default", "--noise");
  EXPECT_EQ(d, default_sensor_noise());
  EXPECT_EQ(d.size(), kChannelCount - 1);  // every channel but t
  const auto changed = parse_sensor_noise("default,f_lift=1e4", "--noise");
  EXPECT_DOUBLE_EQ(changed.at("f_lift"), 1e4);
  EXPECT_DOUBLE_EQ(changed.at("f_tilt"), default_sensor_noise().at("f_tilt"));
  // "5kN" was read as 5 N; a sigma of 1e12 N is no sensor's (at most 100 times the default)
  for (const char* bad : {"t=1", "f_lift", "f_lift=abc", "f_lift=-1", "quiet", "f_lift=5kN",
                          "f_lift=1e12", "v_drive=nan"}) {
    try {
      parse_sensor_noise(bad, "metadata.json: field 'noise'");
      ADD_FAILURE() << bad << " parsed";
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind("metadata.json: field 'noise'", 0), 0u) << msg;
      EXPECT_NE(msg.find(bad), std::string::npos) << msg;
    }
  }
}

// the largest noise synth accepts stays, at five of its standard deviations, within half of what
// the machine can read, so a synthetic run always loads as a measured one (load_measured_run holds
// records to vehicle::reading_limits)
TEST(Synthetic, TheLargestNoiseStaysWithinTheReadings) {
  const vehicle::WheelLoader loader(vehicle::find_data_file("wa320", "machines"));
  const auto limit = vehicle::reading_limits(loader);
  for (const auto& [channel, sigma] : default_sensor_noise()) {
    std::size_t c = 0;
    while (kChannelNames[c] != channel) ++c;
    if (limit[c] == 0.0) continue;  // positions: no machine bound
    EXPECT_LE(5.0 * kMaxNoiseOverDefault * sigma, 0.5 * limit[c]) << channel;
  }
}

// the noise has the asked standard deviation and zero mean on each named channel, leaves t and
// the others alone, and the same seed draws the same noise
TEST(Synthetic, NoiseHasItsSigmaOnItsChannelsOnly) {
  const TimeSeries clean = test::reference_series(1000.0);  // 10 001 samples
  TimeSeries noisy = clean;
  add_sensor_noise(noisy, {{"f_lift", 5e3}, {"v_drive", 0.02}}, 7);
  for (std::size_t c = 0; c < kChannelCount; ++c) {
    double sum = 0.0, sum2 = 0.0;
    const std::size_t n = clean.size();
    for (std::size_t k = 0; k < n; ++k) {
      const double e = noisy.columns[c][k] - clean.columns[c][k];
      sum += e;
      sum2 += e * e;
    }
    const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
    const double want = c == static_cast<std::size_t>(Channel::f_lift) ? 5e3
                        : c == static_cast<std::size_t>(Channel::v_drive) ? 0.02 : 0.0;
    // 10 001 samples: the sample sd within 3 % and the mean within 4 standard errors
    EXPECT_NEAR(sd, want, 0.03 * want) << kChannelNames[c];
    EXPECT_NEAR(mean, 0.0, 4.0 * want / std::sqrt(double(n))) << kChannelNames[c];
  }
  TimeSeries again = clean;
  add_sensor_noise(again, {{"f_lift", 5e3}, {"v_drive", 0.02}}, 7);
  EXPECT_EQ(again.columns, noisy.columns);
}

// no variation is the scenario itself; a variation keeps the breakpoints in order and inside the
// run, and scales each series by at most 1 +- v
TEST(Synthetic, VariedInputsStayOrderedAndBounded) {
  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  const vehicle::Scenario same = varied_inputs(sc, 0.0, 3);
  EXPECT_EQ(same.lift.points(), sc.lift.points());
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const vehicle::Scenario v = varied_inputs(sc, 0.3, seed);
    for (auto [a, b] : {std::pair{&sc.drive, &v.drive}, {&sc.lift, &v.lift}, {&sc.tilt, &v.tilt}}) {
      const auto p = a->points(), q = b->points();
      ASSERT_EQ(p.size(), q.size());
      EXPECT_EQ(q.front().first, p.front().first);
      EXPECT_EQ(q.back().first, p.back().first);
      for (std::size_t i = 1; i < q.size(); ++i) EXPECT_LE(q[i - 1].first, q[i].first) << "seed " << seed;
      for (std::size_t i = 0; i < q.size(); ++i) EXPECT_LE(std::abs(q[i].second), 1.3 * std::abs(p[i].second) + 1e-12);
    }
  }
}

// the digging phase moves with the commands: its start with the drive's inner breakpoints, its
// end with the mean of the lift's and the tilt's, and stays in order inside the run
TEST(Synthetic, VariedInputsShiftTheDigMarksWithTheCommands) {
  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  ASSERT_GT(sc.dig_end, sc.dig_start);
  const vehicle::Scenario same = varied_inputs(sc, 0.0, 3);
  EXPECT_EQ(same.dig_start, sc.dig_start);
  EXPECT_EQ(same.dig_end, sc.dig_end);
  int moved = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const vehicle::Scenario v = varied_inputs(sc, 0.3, seed);
    // the shift of a series: how far its second breakpoint moved
    auto shift = [](const vehicle::PiecewiseLinear& a, const vehicle::PiecewiseLinear& b) {
      return b.points()[1].first - a.points()[1].first;
    };
    const double start = std::clamp(sc.dig_start + shift(sc.drive, v.drive), 0.0, sc.duration);
    const double end = std::clamp(
        sc.dig_end + 0.5 * (shift(sc.lift, v.lift) + shift(sc.tilt, v.tilt)), 0.0, sc.duration);
    if (end > start) {
      EXPECT_NEAR(v.dig_start, start, 1e-12) << "seed " << seed;
      EXPECT_NEAR(v.dig_end, end, 1e-12) << "seed " << seed;
    }
    EXPECT_LT(v.dig_start, v.dig_end);
    EXPECT_GE(v.dig_start, 0.0);
    EXPECT_LE(v.dig_end, sc.duration);
    moved += v.dig_start != sc.dig_start;
  }
  EXPECT_GT(moved, 10);
  // a scenario without marks keeps none
  const vehicle::Scenario carry = varied_inputs(vehicle::load_scenario("load-carry"), 0.3, 5);
  EXPECT_EQ(carry.dig_start, 0.0);
  EXPECT_EQ(carry.dig_end, 0.0);
}

}  // namespace
}  // namespace talus::sim2real
