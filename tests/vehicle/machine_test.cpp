// vehicle/machine: a machine file parsed into a description, and the model built from it or from
// a description made by code
#include "vehicle/machine.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "host/error.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus::vehicle {
namespace {

std::string machine_file() { return find_data_file("wa320", "machines"); }

// what InputError says when `f` throws it
template <class F>
std::string input_error(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError";
  return "";
}

// the description holds the file's values, and the model built from it is the file's model
TEST(Machine, ParsedDescriptionBuildsTheFilesModel) {
  const MachineDescription m = parse_machine(machine_file());
  EXPECT_EQ(m.source, machine_file());
  EXPECT_EQ(m.bodies.size(), 10u);
  EXPECT_EQ(m.hinges.size(), 10u);
  EXPECT_EQ(m.cylinders.size(), 3u);
  const WheelLoader from_file(machine_file(), 1500.0), from_description(m, 1500.0);
  EXPECT_EQ(from_description.operating_mass(), from_file.operating_mass());
  EXPECT_EQ(from_description.bucket_tip_world(), from_file.bucket_tip_world());
  EXPECT_EQ(from_description.lift_spec().force_push, from_file.lift_spec().force_push);
  EXPECT_EQ(from_description.static_tipping_load(), from_file.static_tipping_load());
}

// a machine changed in code, no JSON written: a larger lift bore pushes harder by the area ratio
TEST(Machine, ADescriptionChangedInCodeBuilds) {
  MachineDescription m = parse_machine(machine_file());
  const WheelLoader stock(m);
  for (CylinderDescription& c : m.cylinders)
    if (c.role == "lift") c.bore *= 1.1;
  m.source = "a test's machine";
  const WheelLoader bigger(m);
  EXPECT_NEAR(bigger.lift_spec().force_push / stock.lift_spec().force_push, 1.21, 1e-12);
  EXPECT_EQ(bigger.tilt_spec().force_push, stock.tilt_spec().force_push);
}

// what only the built model can check names the source and the field
TEST(Machine, BuildErrorsNameTheSourceAndTheField) {
  MachineDescription m = parse_machine(machine_file());
  m.source = "code:narrow-loader";
  MachineDescription no_body = m;
  no_body.hinges[2].b = "no_such_body";
  const std::string a = input_error([&] { WheelLoader w(no_body); });
  EXPECT_NE(a.find("code:narrow-loader: field 'hinges[2].b'"), std::string::npos) << a;
  EXPECT_NE(a.find("no_such_body"), std::string::npos) << a;
  MachineDescription short_stroke = m;
  short_stroke.cylinders[0].length_max = short_stroke.cylinders[0].length_min + 1e-3;
  const std::string b = input_error([&] { WheelLoader w(short_stroke); });
  EXPECT_NE(b.find("field 'cylinders[0].length_range'"), std::string::npos) << b;
  // the values a file is checked for are checked in a description made by code too
  MachineDescription weightless = m;
  weightless.bodies[0].mass = 0.0;
  weightless.source.clear();
  const std::string d = input_error([&] { WheelLoader w(weightless); });
  EXPECT_NE(
      d.find("machine '" + m.name + "': field 'bodies[0].mass' is 0 kg; give a value from 1 to"),
      std::string::npos)
      << d;
  MachineDescription infinite = m;
  infinite.cylinders[1].bore = std::numeric_limits<double>::infinity();
  const std::string e = input_error([&] { WheelLoader w(infinite); });
  EXPECT_NE(e.find("field 'cylinders[1].bore' is inf m"), std::string::npos) << e;
  // a cylinder's top speed in (0, 1] m/s: a negative one inverted the clamp of the command
  for (const double speed : {-0.2, 0.0, 1e30}) {
    MachineDescription fast = m;
    fast.cylinders[0].max_speed = speed;
    const std::string s = input_error([&] { WheelLoader w(fast); });
    EXPECT_NE(s.find("field 'cylinders[0].max_speed'"), std::string::npos) << speed << ": " << s;
  }
  MachineDescription two_tilts = m;
  for (CylinderDescription& c : two_tilts.cylinders) c.role = "tilt";
  const std::string c = input_error([&] { WheelLoader w(two_tilts); });
  EXPECT_NE(c.find("is a second tilt cylinder"), std::string::npos) << c;
}

// every value has a physical range with its unit (the class of wheel loaders, machine.cpp): a value
// outside it is refused naming the field, the value and the range. Each case below ran to exit 0
// with the machine at +-85 degrees of pitch or through the ground, or failed inside CHOLMOD
// without naming the field, before (issue 15's audit)
TEST(Machine, ValuesOutsideTheirPhysicalRangeNameFieldValueAndRange) {
  const MachineDescription m = parse_machine(machine_file());
  struct Case {
    std::string field;
    std::function<void(MachineDescription&)> change;
  };
  const std::vector<Case> cases = {
      {"bodies[0].mass", [](MachineDescription& d) { d.bodies[0].mass = 1e9; }},
      {"bodies[3].inertia[1]", [](MachineDescription& d) { d.bodies[3].inertia[1] = -5.0; }},
      {"bodies[3].inertia[1]", [](MachineDescription& d) { d.bodies[3].inertia[1] = 1e12; }},
      // a rod whose moment about its axis exceeds the other two: no mass is distributed so
      {"bodies[5].inertia", [](MachineDescription& d) { d.bodies[5].inertia = Vec3(100, 6, 6); }},
      {"bodies[2].com[2]", [](MachineDescription& d) { d.bodies[2].com[2] = 1e4; }},
      {"solver.joint_compliance", [](MachineDescription& d) { d.joint.compliance = 1.0; }},
      {"solver.joint_damping_time", [](MachineDescription& d) { d.joint.damping_time = -0.1; }},
      {"hinges[0].range[1]",
       [](MachineDescription& d) { d.hinges[0].range = std::make_pair(0.0, 10.0); }},
      {"hinges[1].point[0]", [](MachineDescription& d) { d.hinges[1].point[0] = -1e3; }},
      {"hydraulics.relief_pressure", [](MachineDescription& d) { d.relief_pressure = 31.4; }},
      {"cylinders[2].rod", [](MachineDescription& d) { d.cylinders[2].rod = 0.2; }},
      {"cylinders[0].length_range[1]",
       [](MachineDescription& d) { d.cylinders[0].length_max = 1e3; }},
      {"tyres.radius", [](MachineDescription& d) { d.tyres.radius = 50.0; }},
      {"tyres.elastic_modulus", [](MachineDescription& d) { d.tyres.elastic_modulus = 1.0; }},
      {"tyres.friction", [](MachineDescription& d) { d.tyres.friction = 40.0; }},
      {"driveline.max_power", [](MachineDescription& d) { d.driveline.max_power = 1e12; }},
      {"driveline.rated_motor_speed",
       [](MachineDescription& d) { d.driveline.rated_motor_speed = 2100; }},
      {"driveline.top_speed", [](MachineDescription& d) { d.driveline.top_speed = 360.0; }},
      {"driveline.traction_limit", [](MachineDescription& d) { d.driveline.traction_limit = 0.5; }},
      {"bucket_ground.stiffness", [](MachineDescription& d) { d.bucket_ground.stiffness = 10.0; }},
      {"bucket.rated_volume", [](MachineDescription& d) { d.bucket.rated_volume = 3e3; }},
  };
  for (const Case& c : cases) {
    MachineDescription bad = m;
    c.change(bad);
    const std::string e = input_error([&] { WheelLoader w(bad); });
    EXPECT_NE(e.find(m.source + ": field '" + c.field + "' is "), std::string::npos) << e;
    EXPECT_NE(e.find("give "), std::string::npos) << e;
  }
}

// a machine file with a value out of range names the file and the field before anything is built
TEST(Machine, AFileValueOutOfRangeNamesTheFile) {
  std::ifstream in(machine_file());
  nlohmann::json j = nlohmann::json::parse(in);
  j["tyres"]["radius"]["value"] = 69.5;  // centimetres written as metres
  const std::string path = ::testing::TempDir() + "/talus_machine_range.json";
  std::ofstream(path) << j.dump();
  const std::string e = input_error([&] { parse_machine(path); });
  EXPECT_NE(e.find(path + ": field 'tyres.radius' is 69.5 m; give a value from 0.2 to 2.5 m"),
            std::string::npos)
      << e;
}

}  // namespace
}  // namespace talus::vehicle
