// vehicle/machine: a machine file parsed into a description, and the model built from it or from
// a description made by code
#include "vehicle/machine.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

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
  EXPECT_NE(d.find("machine '" + m.name + "': field 'bodies[0]' has a mass or inertia <= 0"),
            std::string::npos)
      << d;
  MachineDescription infinite = m;
  infinite.cylinders[1].bore = std::numeric_limits<double>::infinity();
  const std::string e = input_error([&] { WheelLoader w(infinite); });
  EXPECT_NE(e.find("field 'cylinders[1]' has a value that is not finite"), std::string::npos) << e;
  MachineDescription two_tilts = m;
  for (CylinderDescription& c : two_tilts.cylinders) c.role = "tilt";
  const std::string c = input_error([&] { WheelLoader w(two_tilts); });
  EXPECT_NE(c.find("is a second tilt cylinder"), std::string::npos) << c;
}

}  // namespace
}  // namespace talus::vehicle
