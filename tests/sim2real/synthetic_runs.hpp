// Small synthetic run pairs whose sim-to-real errors can be worked out by hand (shared by
// tests/sim2real and tests/apps). All values SI.
#pragma once
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "sim2real/timeseries.hpp"

namespace talus::test {

namespace fs = std::filesystem;
using sim2real::Channel;

// a generator with a fresh seed every run, the seed printed so that a failure can be replayed
inline std::mt19937_64 fresh_rng() {
  const unsigned seed = std::random_device{}();
  std::printf("[ seed     ] %u\n", seed);
  return std::mt19937_64(seed);
}

// a fresh directory per test (ctest may run tests in parallel)
inline fs::path fresh_temp_dir(const std::string& tag) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::temp_directory_path() /
                       ("talus-" + tag + "-" + info->test_suite_name() + "-" + info->name() +
                        "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// the reference: 0..10 s at 100 Hz, digging window 2..8 s;
//   f_lift = 50 kN + 5 kN/s · t (max in window 90 kN), f_tilt = 20 kN, f_traction = 60 kN,
//   v_drive = 1 m/s, bucket tip x = 0.1 m/s · t, z = 0 (extent in window 0.6 m);
//   loaded mass 3460 kg, work 209 kJ (FB35 field values)
inline constexpr double kRefRateHz = 100.0;
inline constexpr double kRefDuration = 10.0;
inline constexpr double kDigStart = 2.0;
inline constexpr double kDigEnd = 8.0;

inline sim2real::TimeSeries reference_series(double rate_hz = kRefRateHz, double t_offset = 0.0) {
  sim2real::TimeSeries s;
  const int n = static_cast<int>(std::lround(kRefDuration * rate_hz)) + 1;
  for (int k = 0; k < n; ++k) {
    const double t = t_offset + k / rate_hz;
    s[Channel::t].push_back(t);
    s[Channel::f_lift].push_back(50e3 + 5e3 * t);
    s[Channel::f_tilt].push_back(20e3);
    s[Channel::f_traction].push_back(60e3);
    s[Channel::v_drive].push_back(1.0);
    s[Channel::d_lift].push_back(0.5 + 0.01 * t);
    s[Channel::d_tilt].push_back(0.4);
    s[Channel::boom_deg].push_back(-30.0 + t);
    s[Channel::bucket_deg].push_back(2.0 * t);
    s[Channel::pitch_deg].push_back(0.5);
    s[Channel::x_vehicle].push_back(12.0 - t);
    s[Channel::bucket_tip_x].push_back(0.1 * t);
    s[Channel::bucket_tip_z].push_back(0.0);
    s[Channel::power].push_back(60e3);
  }
  return s;
}

// the simulated run, by construction: inside the window f_lift +9 kN (E_l = 9/90 = 0.1),
// f_tilt ×1.2 (E_t = 0.2), f_traction equal (E_tr = 0, but wildly off outside the window so the
// phase selection is tested), v_drive 0.95 m/s (E_v = 0.05), bucket tip 0.03 m higher
// (E_x = E_mee = 0.03/0.6 = 0.05), mass −10 %, work +10 %; mean = 0.6/7
inline sim2real::TimeSeries simulated_series(double rate_hz = kRefRateHz, double t_offset = 0.0) {
  sim2real::TimeSeries s = reference_series(rate_hz, t_offset);
  for (std::size_t n = 0; n < s.size(); ++n) {
    const double t = s[Channel::t][n];
    s[Channel::f_lift][n] += 9e3;
    s[Channel::f_tilt][n] *= 1.2;
    if (t < kDigStart - 0.5 || t > kDigEnd + 0.5) s[Channel::f_traction][n] = -500e3;
    s[Channel::v_drive][n] = 0.95;
    s[Channel::bucket_tip_z][n] += 0.03;
  }
  return s;
}

inline constexpr double kRefMassKg = 3460.0;
inline constexpr double kRefWorkJ = 209e3;
inline constexpr double kExpectedMean = 0.6 / 7.0;

inline void write_run(const fs::path& dir, const sim2real::TimeSeries& s,
                      const sim2real::RunSummary& summary) {
  fs::create_directories(dir);
  sim2real::save_timeseries(dir / sim2real::kTimeseriesFile, s);
  sim2real::save_summary(dir / sim2real::kSummaryFile, summary);
}

inline sim2real::RunSummary reference_summary() {
  sim2real::RunSummary r;
  r.loaded_mass_kg = kRefMassKg;
  r.work_J = kRefWorkJ;
  r.scenario = "FB35";
  r.fidelity = "field";
  r.dig_start_s = kDigStart;
  r.dig_end_s = kDigEnd;
  return r;
}

inline sim2real::RunSummary simulated_summary(const std::string& fidelity = "D50") {
  sim2real::RunSummary r;
  r.loaded_mass_kg = 0.9 * kRefMassKg;
  r.work_J = 1.1 * kRefWorkJ;
  r.scenario = "FB35";
  r.fidelity = fidelity;
  return r;
}

}  // namespace talus::test
