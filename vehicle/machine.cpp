#include "vehicle/machine.hpp"

#include <cmath>

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

// The physical ranges of a machine's values, wide enough for every wheel loader built, from a
// compact 2 t machine to the largest (LeTourneau L-2350: 262 t operating mass, 4 m tyres, 1.7 MW,
// 40 m^3 bucket; maker's data), and for the wa320 file's own estimates. Beyond them a run pitched
// the machine through +-85 degrees, drove it through the ground with exit 0, or failed inside
// CHOLMOD without naming the field (issue 15's audit, docs/reliability.md).
struct Range {
  double lo, hi;     // inclusive
  const char* unit;  // as the machine file writes it
};
constexpr Range kBodyMass{1.0, 3.0e5, "kg"};    // a pin to the whole largest loader
constexpr double kLargestPart = 20.0;           // m: no body of a loader is longer
constexpr Range kCoordinate{-50.0, 50.0, "m"};  // positions in the reference pose
constexpr Range kCompliance{0.0, 1e-6, "m/N"};  // 1e-6: 0.15 m of give under a 150 kN load
constexpr Range kViscousCompliance{0.0, 1e-6, "m/(N s)"};
constexpr Range kDampingTime{0.0, 1.0, "s"};  // SPEC §2.1: 2-4 steps of 5 ms
constexpr Range kHingeAngle{-M_PI, M_PI, "rad"};
constexpr Range kReliefPressure{5e6, 5e7, "Pa"};  // mobile hydraulics: 10-45 MPa
constexpr Range kBore{0.02, 1.0, "m"};
constexpr Range kCylinderLength{0.05, 20.0, "m"};
constexpr Range kCylinderSpeed{1e-3, kMaxCylinderSpeed, "m/s"};  // wa320: 0.218, 0.25
constexpr Range kTyreRadius{0.2, 2.5, "m"};
constexpr Range kTyreWidth{0.05, 2.0, "m"};
constexpr Range kTyreModulus{1e5, 1e8, "Pa"};  // paper: 1 MPa
constexpr Range kFriction{0.0, 3.0, ""};       // paper: tyres 2.0, bucket-terrain 0.2
constexpr Range kGroundStiffness{1e5, 1e10, "N/m"};
constexpr Range kPower{1e3, 2e6, "W"};                  // paper: 127 kW
constexpr Range kMotorSpeed{50.0, 1500.0, "rad/s"};     // diesels 1800-2200 rpm, e-motors to 14000
constexpr Range kTopSpeed{0.5, kMaxDriveSpeed, "m/s"};  // wa320: 3.61 (digging gear)
constexpr Range kTraction{1e3, 2e6, "N"};
constexpr Range kRatedVolume{0.1, 50.0, "m^3"};

// a value within its range (NaN is not), or one message naming the field, the value and the range
void check_range(const MachineDescription& m, const std::string& field, double v, const Range& r) {
  if (v >= r.lo && v <= r.hi) return;
  const std::string unit = *r.unit ? std::string(" ") + r.unit : std::string();
  fail_field(m, field, "is " + message_number(v) + unit,
             "give a value from " + message_number(r.lo) + " to " + message_number(r.hi) + unit);
}

void check_point(const MachineDescription& m, const std::string& field, const Vec3& p) {
  for (int k = 0; k < 3; ++k)
    check_range(m, field + "[" + std::to_string(k) + "]", p[k], kCoordinate);
}

}  // namespace

void fail_field(const MachineDescription& m, const std::string& field, const std::string& problem,
                const std::string& fix) {
  // a description made by code without a source is named by its machine's name
  const std::string source = m.source.empty() ? "machine '" + m.name + "'" : m.source;
  throw InputError(source + ": field '" + field + "' " + problem + "; " + fix);
}

void check_machine(const MachineDescription& m) {
  // bodies: mass, centre and principal inertia, which a rigid body's mass distribution bounds:
  // each moment at most the sum of the other two, none above the mass at the largest part's length
  if (m.bodies.empty()) fail_field(m, "bodies", "is empty", "list the rigid bodies");
  for (size_t i = 0; i < m.bodies.size(); ++i) {
    const BodyDescription& b = m.bodies[i];
    const std::string where = "bodies[" + std::to_string(i) + "]";
    check_range(m, where + ".mass", b.mass, kBodyMass);
    check_point(m, where + ".com", b.com);
    const Range inertia{1e-6, b.mass * kLargestPart * kLargestPart, "kg m^2"};
    for (int k = 0; k < 3; ++k)
      check_range(m, where + ".inertia[" + std::to_string(k) + "]", b.inertia[k], inertia);
    const Vec3& j = b.inertia;
    constexpr double kRoundOff = 1e-9;  // a thin plate's moments sum exactly
    if (j[0] > (j[1] + j[2]) * (1 + kRoundOff) || j[1] > (j[0] + j[2]) * (1 + kRoundOff) ||
        j[2] > (j[0] + j[1]) * (1 + kRoundOff))
      fail_field(m, where + ".inertia",
                 "is (" + message_number(j[0]) + ", " + message_number(j[1]) + ", " +
                     message_number(j[2]) +
                     ") kg m^2: one moment above the sum of the other two, which no body has",
                 "give the principal moments of a real body");
  }

  // the joints' regularisation
  check_range(m, "solver.joint_compliance", m.joint.compliance, kCompliance);
  check_range(m, "solver.joint_damping_time", m.joint.damping_time, kDampingTime);
  check_range(m, "solver.motor_viscous_compliance", m.motor_viscous_compliance, kViscousCompliance);

  // hinges: a point, a direction, an angle range within one turn
  for (size_t i = 0; i < m.hinges.size(); ++i) {
    const HingeDescription& h = m.hinges[i];
    const std::string where = "hinges[" + std::to_string(i) + "]";
    check_point(m, where + ".point", h.point);
    if (!h.axis.allFinite() || h.axis.norm() < 1e-9)
      fail_field(m, where + ".axis", "is zero or not finite", "give a direction");
    if (h.range) {
      check_range(m, where + ".range[0]", h.range->first, kHingeAngle);
      check_range(m, where + ".range[1]", h.range->second, kHingeAngle);
      if (h.range->first > h.range->second)
        fail_field(m, where + ".range", "is not [lower, upper] with lower <= upper",
                   "give two angles in rad");
    }
  }

  // hydraulics and cylinders: a rod thinner than its bore, a stroke that opens
  check_range(m, "hydraulics.relief_pressure", m.relief_pressure, kReliefPressure);
  for (size_t i = 0; i < m.cylinders.size(); ++i) {
    const CylinderDescription& c = m.cylinders[i];
    const std::string where = "cylinders[" + std::to_string(i) + "]";
    check_point(m, where + ".pin_a", c.pin_a);
    check_point(m, where + ".pin_b", c.pin_b);
    check_range(m, where + ".bore", c.bore, kBore);
    check_range(m, where + ".rod", c.rod, Range{1e-3, c.bore * (1 - 1e-3), "m (below the bore)"});
    // zero never moves the cylinder; a negative speed inverted the clamp of the commanded speed
    // (undefined behaviour: the boom sank when commanded up)
    check_range(m, where + ".max_speed", c.max_speed, kCylinderSpeed);
    check_range(m, where + ".length_range[0]", c.length_min, kCylinderLength);
    check_range(m, where + ".length_range[1]", c.length_max, kCylinderLength);
    if (!(c.length_max > c.length_min))
      fail_field(m, where + ".length_range", "is not [closed, open] with closed < open",
                 "give the closed and open pin-to-pin lengths in m");
  }

  // tyres, driveline, the bucket's ground contact and its rated volume
  const TyreParameters& t = m.tyres;
  check_range(m, "tyres.radius", t.radius, kTyreRadius);
  check_range(m, "tyres.width", t.width, kTyreWidth);
  check_range(m, "tyres.elastic_modulus", t.elastic_modulus, kTyreModulus);
  check_range(m, "tyres.friction", t.friction, kFriction);
  check_range(m, "tyres.damping_time", t.damping_time, kDampingTime);
  check_range(m, "tyres.friction_viscous_compliance", t.viscous_compliance, kViscousCompliance);
  const DrivelineDescription& d = m.driveline;
  check_range(m, "driveline.max_power", d.max_power, kPower);
  check_range(m, "driveline.rated_motor_speed", d.rated_motor_speed, kMotorSpeed);
  check_range(m, "driveline.top_speed", d.top_speed, kTopSpeed);
  check_range(m, "driveline.traction_limit", d.traction_limit, kTraction);
  const GroundContactParameters& g = m.bucket_ground;
  check_range(m, "bucket_ground.stiffness", g.stiffness, kGroundStiffness);
  check_range(m, "bucket_ground.friction", g.friction, kFriction);
  check_range(m, "bucket_ground.damping_time", g.damping_time, kDampingTime);
  check_range(m, "bucket_ground.friction_viscous_compliance", g.viscous_compliance,
              kViscousCompliance);
  check_point(m, "bucket.tip", m.bucket.tip);
  check_range(m, "bucket.rated_volume", m.bucket.rated_volume, kRatedVolume);
}

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
    h.point = f.vec3(hinges[i], where, "point");
    h.name = f.text(hinges[i], where, "name");
    if (hinges[i].contains("range")) {
      h.range = number_pair(f, hinges[i], where, "range", "is not two numbers",
                            "give [lower, upper] in rad");
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

  // driveline
  const auto& dl = f.member(root, "", "driveline");
  DrivelineDescription& d = m.driveline;
  d.max_power = f.number(dl, "driveline", "max_power");
  d.rated_motor_speed = f.number(dl, "driveline", "rated_motor_speed");
  d.top_speed = f.number(dl, "driveline", "top_speed");
  d.traction_limit = f.number(dl, "driveline", "traction_limit");
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
  // every value within its physical range, as for a description made by code
  check_machine(m);
  return m;
}

}  // namespace talus::vehicle
