// Sensors: the CSV contract, the 100 Hz log, and power and work against their definitions.
#include "vehicle/sensors.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <sstream>

#include "vehicle/data_file.hpp"

namespace talus::vehicle {
namespace {

TEST(SensorTest, CsvHeaderIsTheRunContract) {
  EXPECT_STREQ(sensor_csv_header(),
               "t,f_lift,f_tilt,f_traction,v_drive,d_lift,d_tilt,boom_deg,bucket_deg,pitch_deg,x_vehicle,"
               "bucket_tip_x,bucket_tip_z,power");
  std::ostringstream row;
  write_sensor_csv_row(row, SensorSample{});
  const std::string text = row.str();
  EXPECT_EQ(std::count(text.begin(), text.end(), ','), 13);
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

}  // namespace
}  // namespace talus::vehicle
