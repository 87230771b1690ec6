// The wheel loader built from data/machines/wa320.json, held to the issue's physical anchors.
#include "vehicle/wheel_loader.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <string>

#include "host/error.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/scenario.hpp"
#include "vehicle/sensors.hpp"

namespace talus::vehicle {
namespace {

constexpr double kG = 9.81;
constexpr double kH = 0.005;  // s, the scenarios' timestep

std::string machine() { return find_data_file("wa320", "machines"); }

// the ground's normal force on the machine: the four tyres and the bucket's bottom corners
double normal_sum(const WheelLoader& w) {
  double n = w.bucket_ground().normal_force();
  for (const auto* t : w.tyres()) n += t->normal_force();
  return n;
}

TEST(WheelLoaderTest, ModelHasTheIssuesBodiesAndJoints) {
  WheelLoader w(machine());
  EXPECT_EQ(w.bodies().size(), 10u);
  int hinges = 0, cylinders = 0;
  for (auto* j : w.joints()) {
    hinges += dynamic_cast<HingeJoint*>(j) != nullptr;
    cylinders += dynamic_cast<CylinderJoint*>(j) != nullptr;
  }
  EXPECT_EQ(hinges, 10);
  EXPECT_EQ(cylinders, 3);
  EXPECT_NEAR(w.operating_mass(), 15175.0, 1e-9);  // paper: operating mass 15.175 t
}

// at rest on flat ground: the normal forces of tyres and bucket sum to m g within 0.5 %, creep below 1 mm in 10 s
TEST(WheelLoaderTest, AtRestCarriesItsWeightWithoutCreep) {
  WheelLoader w(machine());
  const Vec3 start = w.bodies()[w.front_frame()].position;
  // settle onto the tyres for 2 s, then measure over 10 s
  for (int k = 0; k < 400; ++k) w.step(kH);
  const Vec3 settled = w.bodies()[w.front_frame()].position;
  double worst_force = 0.0, worst_joint = 0.0;
  for (int k = 0; k < 2000; ++k) {
    w.step(kH);
    const double weight = w.operating_mass() * kG;
    worst_force = std::max(worst_force, std::abs(normal_sum(w) - weight) / weight);
    worst_joint = std::max(worst_joint, w.system().max_joint_position_violation());
  }
  const Vec3 end = w.bodies()[w.front_frame()].position;
  const double creep = std::hypot(end.x() - settled.x(), end.y() - settled.y());
  std::cout << "[ measured ] normal-force error " << worst_force * 100 << " %, creep " << creep * 1e3
            << " mm, joint violation " << worst_joint * 1e3 << " mm, sink " << (start.z() - end.z()) * 1e3 << " mm\n";
  EXPECT_LT(worst_force, 0.005);
  EXPECT_LT(creep, 1e-3);
  EXPECT_LT(worst_joint, 1e-3);
}


// driving at full command: tractive power never above 127 kW; top speed as the data file states
TEST(DrivelineTest, PowerLimitAndTopSpeed) {
  WheelLoader w(machine());
  for (int k = 0; k < 200; ++k) w.step(kH);  // settle on the tyres
  w.set_drive_speed(10.0);                    // more than the machine can: clipped to top speed
  double peak_power = 0.0;
  for (int k = 0; k < 1600; ++k) {
    w.step(kH);
    const auto s = read_sensors(w, w.system().time());
    peak_power = std::max(peak_power, s.f_traction * s.v_drive);
    // the engine's own power: torque times motor speed
    const double engine = w.driveline().motor_torque() * w.driveline().motor_speed(w.bodies());
    ASSERT_LE(engine, w.max_power() * (1 + 1e-9)) << "t = " << w.system().time();
  }
  const double v = w.driveline().drive_speed(w.bodies());
  std::cout << "[ measured ] peak tractive power " << peak_power / 1e3 << " kW, speed after 8 s " << v << " m/s\n";
  EXPECT_LE(peak_power, w.max_power() * (1 + 1e-6));
  EXPECT_GT(peak_power, 0.9 * w.max_power());  // the limit was reached, so the test says something
  EXPECT_NEAR(v, w.top_speed(), 0.01 * w.top_speed());
}

// the particle coupling solves one step several times with different wrenches on the bucket: the
// answer to a wrench must not depend on an earlier solve of the same step (the engine's torque
// limit, lowered for the speed of a lighter load, must not stick)
TEST(DrivelineTest, ResolvingAStepWithAnotherWrenchForgetsTheEarlierSolve) {
  WheelLoader a(machine()), b(machine());
  for (WheelLoader* w : {&a, &b}) {
    for (int k = 0; k < 200; ++k) w->step(kH);
    w->set_drive_speed(w->top_speed());
    for (int k = 0; k < 600; ++k) w->step(kH);  // at speed: power-limited torque
  }
  // a: first solved with a 60 kN push on the bucket (the machine speeds up, so the power limit
  // lowers the engine torque for that solve), then with a 60 kN drag; b: with the drag at once
  Vec6 drag = Vec6::Zero();
  drag[0] = -60e3;
  a.system().assemble(kH);
  a.set_bucket_wrench(-drag);
  a.system().solve();
  a.set_bucket_wrench(drag);
  a.system().solve();
  b.system().assemble(kH);
  b.set_bucket_wrench(drag);
  b.system().solve();
  double worst = 0.0;
  for (int i = 0; i < static_cast<int>(a.bodies().size()); ++i)
    worst = std::max(worst, (a.system().solved_twist(i) - b.system().solved_twist(i)).norm());
  std::cout << "[ measured ] largest twist difference between the two solve orders " << worst << "\n";
  EXPECT_LT(worst, 1e-9);
}

// against a fixed rig the engine stalls at its torque limit: traction = the data file's limit
TEST(DrivelineTest, TractionLimitAgainstFixedRig) {
  WheelLoader w(machine());
  auto& sys = w.system();
  for (int k = 0; k < 200; ++k) w.step(kH);
  sys.add_constraint(std::make_unique<LockJoint>(sys.bodies(), kWorld, w.front_frame(),
                                                 sys.body(w.front_frame()).position));
  w.set_drive_speed(w.top_speed());
  for (int k = 0; k < 200; ++k) w.step(kH);
  const auto s = read_sensors(w, sys.time());
  std::cout << "[ measured ] traction against the rig " << s.f_traction / 1e3 << " kN\n";
  EXPECT_NEAR(s.f_traction, w.traction_limit(), 0.01 * w.traction_limit());
}

// a 3.5 t payload lifted from the ground to full height at full cylinder speed: the time matches
// stroke / cylinder speed, and the lift force stays in its range
TEST(WheelLoaderTest, LoadedLiftTimeMatchesCylinderSpeed) {
  WheelLoader w(machine(), 3500.0);
  for (int k = 0; k < 200; ++k) w.step(kH);
  const double d0 = read_sensors(w, 0).d_lift;
  const double stroke = w.lift_spec().length_max - w.lift_spec().length_min;
  const double expected = (stroke - d0) / w.lift_spec().max_speed;
  w.set_lift_speed(w.lift_spec().max_speed);
  const double t0 = w.system().time();
  double t_full = -1.0;
  for (int k = 0; k < 3000 && t_full < 0; ++k) {
    w.step(kH);
    for (const auto* c : w.lift_cylinders()) {
      ASSERT_LE(c->motor_force(), w.lift_spec().force_push * (1 + 1e-9));
      ASSERT_GE(c->motor_force(), -w.lift_spec().force_pull * (1 + 1e-9));
    }
    if (read_sensors(w, 0).d_lift >= stroke - 1e-3) t_full = w.system().time() - t0;
  }
  const auto s = read_sensors(w, 0);
  std::cout << "[ measured ] lift time " << t_full << " s (stroke/speed " << expected << " s), boom " << s.boom_deg
            << " deg, bucket " << s.bucket_deg << " deg, tip z " << s.bucket_tip_z << " m, f_lift " << s.f_lift / 1e3
            << " kN\n";
  ASSERT_GT(t_full, 0.0);
  EXPECT_NEAR(t_full, expected, 0.03 * expected + 0.05);
  EXPECT_GT(s.bucket_tip_z, 3.5);  // full height: class data hinge-pin height about 3.9 m
}

// the machine posed at its longest reach: settled on its tyres, the bucket curled about 29 deg,
// the boom raised to about -6 deg (near horizontal), then held still for 3 s
void pose_at_full_reach(WheelLoader& w) {
  const auto run = [&](double seconds, double lift, double tilt) {
    w.set_lift_speed(lift);
    w.set_tilt_speed(tilt);
    for (int k = 0; k < static_cast<int>(std::lround(seconds / kH)); ++k) w.step(kH);
  };
  run(0.2, 0.0, 0.0);
  run(0.9, 0.0, 0.15);
  run(5.4, 0.1, 0.0);
  run(3.0, 0.0, 0.0);
}

// static stability: the payload the moment balance says tips the machine (static_tipping_load)
// against the class data, and against the dynamics.
// - The straight tipping load at full reach lies in the class's band: at least the WA320-5's
//   full-turn tipping load scaled to this machine's mass (11.02 t at 14.56 t operating mass, a
//   ratio of 0.757, Marini, "Test macchine" n. 63: 11.5 t; straight is always above full turn) and
//   at most 1.2 times that (straight over full-turn load of articulated loaders, about 1.1-1.2):
//   measured 12.8 t (docs/vehicle.md, "Static stability").
// - Empty and at half of it, the rear tyres carry what the balance in the same pose predicts,
//   (T - P) g arm / wheelbase, within 5 % (measured: 90.4 kN against 90.4 kN empty, 41.0 against
//   42.1 kN at half).
// - ISO 14397-1: a machine sold with a 3.0 m^3 bucket for 1727 kg/m^3 gravel must hold twice
//   its heaped load (10.4 t) at full reach: the rear tyres stay on the ground (measured 10.8 kN)
//   although the soft tyres (the paper's 1 MPa) pitch the machine 4 deg forward; at 110 % of T
//   they are off the ground.
TEST(WheelLoaderTest, StaticTippingLoadMeetsTheClassDataAndTheDynamics) {
  WheelLoader empty(machine());
  pose_at_full_reach(empty);
  const double tipping = empty.static_tipping_load();
  const auto s = read_sensors(empty, 0);
  std::cout << "[ measured ] static tipping load at boom " << s.boom_deg << " deg, bucket " << s.bucket_deg
            << " deg: " << tipping << " kg\n";
  constexpr double kFullTurnPerMass = 11020.0 / 14560.0;  // WA320-5 (Marini, Test macchine n. 63)
  const double class_floor = kFullTurnPerMass * empty.operating_mass();
  EXPECT_GT(tipping, class_floor);
  EXPECT_LT(tipping, 1.2 * class_floor);
  // the rear tyres' load with a payload, posed the same way, and what the balance predicts
  struct RearLoad {
    double measured, predicted, balance;
  };
  const auto rear_load = [&](double payload) {
    WheelLoader w(machine(), payload);
    pose_at_full_reach(w);
    const double x_front = w.bodies()[w.tyres()[0]->wheel()].position.x();
    const double wheelbase = x_front - w.bodies()[w.tyres()[2]->wheel()].position.x();
    const double arm = w.payload_point_world().x() - x_front;
    return RearLoad{w.tyres()[2]->normal_force() + w.tyres()[3]->normal_force(),
                    (w.static_tipping_load() - payload) * kG * arm / wheelbase, w.static_tipping_load()};
  };
  for (const double share : {0.0, 0.5}) {
    const RearLoad r = rear_load(share * tipping);
    std::cout << "[ measured ] rear tyres at " << 100 * share << " % of it: " << r.measured / 1e3
              << " kN (moment balance " << r.predicted / 1e3 << " kN)\n";
    EXPECT_NEAR(r.measured, r.predicted, 0.05 * r.predicted);
  }
  // twice the heaped 3.0 m^3 of the field's gravel (ISO 14397-1's operating load is half the
  // tipping load): held, and the balance in that pose agrees
  constexpr double kIsoPayload = 2.0 * 3.0 * 1727.0;  // kg
  const RearLoad iso = rear_load(kIsoPayload), over = rear_load(1.1 * tipping);
  std::cout << "[ measured ] rear tyres with " << kIsoPayload << " kg: " << iso.measured / 1e3
            << " kN (balance in that pose: T " << iso.balance << " kg), at 110 % of T: " << over.measured / 1e3
            << " kN\n";
  EXPECT_GT(iso.measured, 100.0);  // N: still on the ground
  EXPECT_GT(iso.balance, kIsoPayload);
  EXPECT_LT(over.measured, 100.0);  // N: off the ground
}

// overload on a fixed rig: the lift cylinders stall at their force limit and do not extend
TEST(MotorTest, OverloadedLiftStallsAtForceLimit) {
  WheelLoader w(machine(), 60000.0);
  auto& sys = w.system();
  sys.add_constraint(std::make_unique<LockJoint>(sys.bodies(), kWorld, w.front_frame(),
                                                 sys.body(w.front_frame()).position));
  for (int k = 0; k < 100; ++k) w.step(kH);
  const double d0 = read_sensors(w, 0).d_lift;
  w.set_lift_speed(w.lift_spec().max_speed);
  for (int k = 0; k < 400; ++k) w.step(kH);
  const auto s = read_sensors(w, 0);
  for (const auto* c : w.lift_cylinders()) {
    EXPECT_NEAR(c->motor_force(), w.lift_spec().force_push, 1e-6 * w.lift_spec().force_push);
  }
  std::cout << "[ measured ] overload: lift motor force " << w.lift_cylinders()[0]->motor_force() / 1e3
            << " kN per cylinder (limit " << w.lift_spec().force_push / 1e3 << " kN), extension change "
            << (s.d_lift - d0) * 1e3 << " mm\n";
  EXPECT_LE(s.d_lift, d0 + 1e-3);
}

// cylinders at full force against a fixed obstacle: every joint stays within 1 mm
TEST(JointTest, ViolationBelow1mmWithCylindersAtFullForce) {
  WheelLoader w(machine());
  auto& sys = w.system();
  for (int k = 0; k < 200; ++k) w.step(kH);
  sys.add_constraint(std::make_unique<LockJoint>(sys.bodies(), kWorld, w.front_frame(),
                                                 sys.body(w.front_frame()).position));
  sys.add_constraint(std::make_unique<LockJoint>(sys.bodies(), kWorld, w.bucket_body(),
                                                 sys.body(w.bucket_body()).position));
  w.set_lift_speed(w.lift_spec().max_speed);
  w.set_tilt_speed(w.tilt_spec().max_speed);
  double worst = 0.0;
  for (int k = 0; k < 400; ++k) {
    w.step(kH);
    worst = std::max(worst, sys.max_joint_position_violation());
  }
  sys.assemble(kH);  // violation at the final state
  worst = std::max(worst, sys.max_joint_position_violation());
  std::cout << "[ measured ] full-force joint violation " << worst * 1e3 << " mm, f_lift "
            << w.lift_cylinders()[0]->motor_force() / 1e3 << " kN per cylinder, f_tilt "
            << w.tilt_cylinder().motor_force() / 1e3 << " kN\n";
  EXPECT_NEAR(w.lift_cylinders()[0]->motor_force(), w.lift_spec().force_push, 1e-6 * w.lift_spec().force_push);
  EXPECT_NEAR(w.tilt_cylinder().motor_force(), w.tilt_spec().force_push, 1e-6 * w.tilt_spec().force_push);
  EXPECT_LT(worst, 1e-3);
}

// the bucket's articulated mobility matches re-solving the step with a small impulse on the bucket
TEST(WheelLoaderTest, BucketMobilityMatchesFiniteDifference) {
  WheelLoader w(machine(), 1000.0);
  for (int k = 0; k < 300; ++k) w.step(kH);
  w.set_lift_speed(0.1);
  auto& sys = w.system();
  sys.assemble(kH);
  sys.solve();
  const Mat6 W = w.bucket_mobility();
  const Vec6 v0 = sys.solved_twist(w.bucket_body());
  const double p = 1.0;  // N s: small against the bucket's 2 t and the solver's force ranges
  Mat6 fd;
  for (int k = 0; k < 6; ++k) {
    w.set_bucket_wrench(Vec6::Unit(k) * (p / kH));
    sys.solve();
    fd.col(k) = (sys.solved_twist(w.bucket_body()) - v0) / p;
  }
  const double err = (W - fd).cwiseAbs().maxCoeff() / W.cwiseAbs().maxCoeff();
  std::cout << "[ measured ] bucket mobility vs finite difference: relative error " << err << "\n";
  EXPECT_LT(err, 1e-6);
  // the articulated bucket is far less mobile than a free one (1/m) along x
  EXPECT_LT(W(0, 0), 1.0 / sys.body(w.bucket_body()).mass);
}

// the tipping load at full reach from the machine's own pose (boom level) lies in the class's
// band as the test above's hand pose does, and a payload above half of it (ISO 14397-1's rated
// load) runs with a warning naming the file, the rated load and the tipping load (load-carry with
// 7 t pitches to -12 deg, with 9 t to -41 deg: docs/vehicle.md)
TEST(WheelLoaderTest, APayloadAboveTheRatedLoadGetsAWarning) {
  const MachineDescription m = parse_machine(machine());
  const double tipping = full_reach_tipping_load(m);
  std::cout << "[ measured ] static tipping load with the boom level: " << tipping << " kg\n";
  constexpr double kFullTurnPerMass = 11020.0 / 14560.0;  // WA320-5 (Marini, Test macchine n. 63)
  const double class_floor = kFullTurnPerMass * WheelLoader(m).operating_mass();
  EXPECT_GT(tipping, class_floor);
  EXPECT_LT(tipping, 1.2 * class_floor);
  Scenario sc = load_scenario("load-carry");
  EXPECT_EQ(payload_warning(sc, m), "") << "3.5 t is within the rating";
  sc.payload = 7000.0;
  const std::string w = payload_warning(sc, m);
  EXPECT_NE(w.find("load-carry.json: payload 7000 kg is above the rated operating load of wa320"),
            std::string::npos)
      << w;
  EXPECT_NE(w.find(std::to_string(std::lround(tipping)) + " kg, ISO 14397-1"), std::string::npos)
      << w;
}

}  // namespace
}  // namespace talus::vehicle
