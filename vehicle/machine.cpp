#include "vehicle/machine.hpp"

#include "host/error.hpp"
#include "vehicle/data_file.hpp"

namespace talus::vehicle {

namespace {

// a sourced pair of numbers [lower, upper] (a range) or [x, z]; `shape` and `fix` for the message
std::pair<double, double> number_pair(const DataFile& f, const nlohmann::json& j,
                                      const std::string& where, const std::string& key,
                                      const std::string& shape, const std::string& fix) {
  const auto& v = f.quantity(j, where, key);
  if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number())
    f.fail(where + "." + key + ".value", shape, fix);
  return {v[0].get<double>(), v[1].get<double>()};
}

}  // namespace

MachineDescription parse_machine(const std::string& file) {
  const DataFile f(file);
  const auto& root = f.root();
  MachineDescription m;
  m.source = file;
  m.name = f.text(root, "", "name");

  // solver parameters shared by all joints
  const auto& solver = f.member(root, "", "solver");
  m.joint.compliance = f.number(solver, "solver", "joint_compliance");
  m.joint.damping_time = f.number(solver, "solver", "joint_damping_time");
  m.motor_viscous_compliance = f.number(solver, "solver", "motor_viscous_compliance");
  if (m.joint.compliance < 0 || m.joint.damping_time < 0 || m.motor_viscous_compliance < 0) {
    f.fail("solver", "has a negative compliance or damping time", "use values >= 0");
  }

  // bodies
  const auto& bodies = f.member(root, "", "bodies");
  if (!bodies.is_array() || bodies.empty())
    f.fail("bodies", "is not a non-empty array", "list the rigid bodies");
  for (size_t i = 0; i < bodies.size(); ++i) {
    const std::string where = "bodies[" + std::to_string(i) + "]";
    BodyDescription b;
    b.name = f.text(bodies[i], where, "name");
    b.mass = f.number(bodies[i], where, "mass");
    b.com = f.vec3(bodies[i], where, "com");
    b.inertia = f.vec3(bodies[i], where, "inertia");
    if (!(b.mass > 0) || !(b.inertia.minCoeff() > 0))
      f.fail(where, "has a mass or inertia <= 0", "give positive values");
    m.bodies.push_back(b);
  }

  // the bucket
  const auto& bk = f.member(root, "", "bucket");
  m.bucket.body = f.text(bk, "bucket", "body");
  BucketGeometry& g = m.bucket.geometry;
  g.width = f.number(bk, "bucket", "width");
  g.side_plate = f.number(bk, "bucket", "side_plate");
  g.bottom_length = f.number(bk, "bucket", "bottom_length");
  g.corner_radius = f.number(bk, "bucket", "corner_radius");
  g.back_height = f.number(bk, "bucket", "back_height");
  g.edge_length = f.number(bk, "bucket", "edge_length");
  const auto lip = number_pair(f, bk, "bucket", "lip", "is not two numbers",
                               "give [x, z] of the top lip relative to the cutting edge");
  g.lip = Vec3(lip.first, 0.0, lip.second);
  m.bucket.rated_volume = f.number(bk, "bucket", "rated_volume");
  m.bucket.tip = f.vec3(bk, "bucket", "tip");

  // hinges
  const auto& hinges = f.member(root, "", "hinges");
  if (!hinges.is_array()) f.fail("hinges", "is not an array", "list the hinge joints");
  for (size_t i = 0; i < hinges.size(); ++i) {
    const std::string where = "hinges[" + std::to_string(i) + "]";
    HingeDescription h;
    h.a = f.text(hinges[i], where, "a");
    h.b = f.text(hinges[i], where, "b");
    h.axis = f.vec3(hinges[i], where, "axis");
    if (h.axis.norm() < 1e-9) f.fail(where + ".axis", "is zero", "give a direction");
    h.point = f.vec3(hinges[i], where, "point");
    h.name = f.text(hinges[i], where, "name");
    if (hinges[i].contains("range")) {
      h.range = number_pair(f, hinges[i], where, "range",
                            "is not [lower, upper] with lower <= upper", "give two angles in rad");
      if (h.range->first > h.range->second)
        f.fail(where + ".range.value", "is not [lower, upper] with lower <= upper",
               "give two angles in rad");
    }
    m.hinges.push_back(h);
  }

  // cylinders
  m.relief_pressure = f.number(f.member(root, "", "hydraulics"), "hydraulics", "relief_pressure");
  const auto& cylinders = f.member(root, "", "cylinders");
  for (size_t i = 0; i < cylinders.size(); ++i) {
    const std::string where = "cylinders[" + std::to_string(i) + "]";
    const auto& c = cylinders[i];
    CylinderDescription d;
    d.a = f.text(c, where, "a");
    d.b = f.text(c, where, "b");
    d.pin_a = f.vec3(c, where, "pin_a");
    d.pin_b = f.vec3(c, where, "pin_b");
    d.name = f.text(c, where, "name");
    d.bore = f.number(c, where, "bore");
    d.rod = f.number(c, where, "rod");
    if (!(d.bore > d.rod) || !(d.rod > 0))
      f.fail(where, "has bore <= rod or rod <= 0", "give bore > rod > 0 in metres");
    d.max_speed = f.number(c, where, "max_speed");
    const auto range = number_pair(f, c, where, "length_range", "is not [min, max]",
                                   "give the closed and open pin-to-pin lengths in m");
    d.length_min = range.first;
    d.length_max = range.second;
    d.role = f.text(c, where, "role");
    if (d.role != "lift" && d.role != "tilt")
      f.fail(where + ".role", "is '" + d.role + "'", "use \"lift\" or \"tilt\"");
    m.cylinders.push_back(d);
  }

  // tyres
  const auto& ty = f.member(root, "", "tyres");
  TyreParameters& tp = m.tyres;
  tp.radius = f.number(ty, "tyres", "radius");
  tp.width = f.number(ty, "tyres", "width");
  tp.elastic_modulus = f.number(ty, "tyres", "elastic_modulus");
  tp.friction = f.number(ty, "tyres", "friction");
  tp.damping_time = f.number(ty, "tyres", "damping_time");
  tp.viscous_compliance = f.number(ty, "tyres", "friction_viscous_compliance");
  if (!(tp.radius > 0) || !(tp.width > 0) || !(tp.elastic_modulus > 0) || !(tp.friction >= 0)) {
    f.fail("tyres", "has a non-positive size, modulus or a negative friction",
           "correct the values");
  }

  // driveline
  const auto& dl = f.member(root, "", "driveline");
  DrivelineDescription& d = m.driveline;
  d.max_power = f.number(dl, "driveline", "max_power");
  d.rated_motor_speed = f.number(dl, "driveline", "rated_motor_speed");
  d.top_speed = f.number(dl, "driveline", "top_speed");
  d.traction_limit = f.number(dl, "driveline", "traction_limit");
  if (!(d.max_power > 0) || !(d.rated_motor_speed > 0) || !(d.top_speed > 0) ||
      !(d.traction_limit > 0)) {
    f.fail("driveline", "has a value <= 0", "give positive power, speeds and traction");
  }
  const auto& wheels = f.quantity(dl, "driveline", "wheels");
  if (!wheels.is_array() || wheels.size() != 4)
    f.fail("driveline.wheels.value", "is not four names", "list FL, FR, RL, RR");
  for (int i = 0; i < 4; ++i) {
    if (!wheels[i].is_string())
      f.fail("driveline.wheels.value", "has a non-string entry", "list body names");
    d.wheels[i] = wheels[i].get<std::string>();
  }

  // the bucket's bottom corners against the ground
  const auto& bg = f.member(root, "", "bucket_ground");
  GroundContactParameters& gp = m.bucket_ground;
  gp.stiffness = f.number(bg, "bucket_ground", "stiffness");
  gp.friction = f.number(bg, "bucket_ground", "friction");
  gp.damping_time = f.number(bg, "bucket_ground", "damping_time");
  gp.viscous_compliance = f.number(bg, "bucket_ground", "friction_viscous_compliance");
  if (!(gp.stiffness > 0) || !(gp.friction >= 0) || !(gp.damping_time >= 0) ||
      !(gp.viscous_compliance >= 0))
    f.fail("bucket_ground", "has a non-positive stiffness or a negative friction or damping",
           "correct the values");
  return m;
}

}  // namespace talus::vehicle
