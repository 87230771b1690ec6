// Sensors: the CSV contract, the 100 Hz log, and power and work against their definitions.
#include "vehicle/sensors.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <sstream>

#include "host/error.hpp"
#include "vehicle/data_file.hpp"

namespace talus::vehicle {
namespace {

// the header is the contract of SPEC §2.4 written out here by hand (a witness independent of the
// channel table), and each column carries its own field: a sample whose fields hold their column's
// index writes 0,1,...,13; a value that needs all of a double's digits is written with them
TEST(SensorTest, CsvIsTheRunContract) {
  SensorSample s;
  s.t = 0, s.f_lift = 1, s.f_tilt = 2, s.f_traction = 3, s.v_drive = 4, s.d_lift = 5, s.d_tilt = 6;
  s.boom_deg = 7, s.bucket_deg = 8, s.pitch_deg = 9, s.x_vehicle = 10, s.bucket_tip_x = 11;
  s.bucket_tip_z = 12, s.power = 13, s.lift_rate = 99, s.tilt_rate = 99;
  SensorSample exact = s;
  exact.t = 0.1;
  exact.power = 1.0 / 3.0;
  EXPECT_EQ(sensor_csv({s, exact}),
            "t,f_lift,f_tilt,f_traction,v_drive,d_lift,d_tilt,boom_deg,bucket_deg,pitch_deg,x_vehicle,"
            "bucket_tip_x,bucket_tip_z,power\n"
            "0,1,2,3,4,5,6,7,8,9,10,11,12,13\n"
            "0.10000000000000001,1,2,3,4,5,6,7,8,9,10,11,12,0.33333333333333331\n");
}

// lifting at constant speed: 100 Hz samples, power = f_l ḋ_l (no driving, tilt held), and the work
// equals the potential energy gained by the lifted bodies within a few percent
TEST(SensorTest, LogAt100HzAndWorkMatchesPotentialEnergy) {
  WheelLoader w(find_data_file("wa320", "machines"), 2000.0);
  const double h = 0.005;
  // settle on the tyres with the bucket raised clear of the ground (no bucket-ground contact)
  w.set_lift_speed(0.15);
  for (int k = 0; k < 100; ++k) w.step(h);
  w.set_lift_speed(0.0);
  for (int k = 0; k < 200; ++k) w.step(h);
  ASSERT_GT(w.bucket_ground().clearance(), 0.01);
  auto height = [&] {
    double e = 0.0;
    for (const auto& b : w.bodies()) e += b.mass * 9.81 * b.position.z();
    return e;
  };
  const double e0 = height();
  SensorLog log(100.0);
  log.after_step(w, 0.0, 0.0);
  w.set_lift_speed(0.15);
  for (int k = 1; k <= 400; ++k) {
    w.step(h);
    log.after_step(w, k * h, h);
  }
  EXPECT_EQ(log.samples().size(), 201u);  // 0 .. 2 s at 10 ms
  EXPECT_NEAR(log.samples()[100].t, 1.0, 1e-12);
  const auto& s = log.samples().back();
  EXPECT_NEAR(s.power, s.f_lift * s.lift_rate + s.f_tilt * s.tilt_rate + s.f_traction * s.v_drive, 1e-6);
  const double gained = height() - e0;
  std::cout << "[ measured ] work " << log.work() / 1e3 << " kJ vs potential energy gained " << gained / 1e3 << " kJ\n";
  EXPECT_NEAR(log.work(), gained, 0.03 * gained);
  // boom angle rises while lifting; pitch stays small on flat ground
  EXPECT_GT(s.boom_deg, log.samples().front().boom_deg + 5.0);
  EXPECT_LT(std::abs(s.pitch_deg), 2.0);
}

// steps longer than the 10 ms period (D400: 20 ms) still give 100 Hz samples, the ones between
// steps interpolated; a shorter step samples its own states
TEST(SensorTest, LongStepsAreSampledAt100HzByInterpolation) {
  WheelLoader w(find_data_file("wa320", "machines"));
  SensorLog log(100.0);
  log.after_step(w, 0.0, 0.0);
  w.set_lift_speed(0.1);
  const double h = 0.02;
  std::vector<SensorSample> after_steps;
  for (int k = 1; k <= 50; ++k) {
    w.step(h);
    log.after_step(w, k * h, h);
    after_steps.push_back(log.samples().back());
  }
  ASSERT_EQ(log.samples().size(), 101u);  // 0 .. 1 s at 10 ms
  for (size_t i = 0; i < log.samples().size(); ++i) EXPECT_NEAR(log.samples()[i].t, 0.01 * i, 1e-12);
  // the sample at 0.03 s lies halfway between the steps ending at 0.02 s and 0.04 s
  const SensorSample mid = interpolate(log.samples()[2], log.samples()[4], 0.5);
  EXPECT_NEAR(log.samples()[3].d_lift, mid.d_lift, 1e-12);
  EXPECT_NEAR(log.samples()[3].f_lift, mid.f_lift, 1e-9);
}

TEST(SensorTest, LogRejectsCallsOutOfOrder) {
  WheelLoader w(find_data_file("wa320", "machines"));
  SensorLog late(100.0);
  EXPECT_THROW(late.after_step(w, 0.5, 0.01), talus::Error);  // the first sample must be at t = 0
  SensorLog log(100.0);
  log.after_step(w, 0.0, 0.0);
  w.step(0.01);
  log.after_step(w, 0.01, 0.01);
  EXPECT_THROW(log.after_step(w, 0.5, 0.0), talus::Error);   // a jump without a step
  EXPECT_THROW(log.after_step(w, 0.01, 0.01), talus::Error);  // not later than before
}

TEST(SensorTest, WorkBetweenIntegratesThePowerOverAWindow) {
  // power rising linearly, P = 1000 t W, sampled at 100 Hz: the work over [0.125, 0.5] s is
  // 500 (0.5^2 - 0.125^2) J exactly (trapezoids are exact for a linear power)
  std::vector<SensorSample> samples;
  for (int k = 0; k <= 100; ++k) {
    SensorSample s;
    s.t = 0.01 * k;
    s.power = 1000.0 * s.t;
    samples.push_back(s);
  }
  EXPECT_NEAR(work_between(samples, 0.125, 0.5), 500.0 * (0.25 - 0.015625), 1e-9);
  EXPECT_NEAR(work_between(samples, 0.0, 1.0), 500.0, 1e-9);
  EXPECT_EQ(work_between(samples, 2.0, 3.0), 0.0);  // outside the log
}

}  // namespace
}  // namespace talus::vehicle
