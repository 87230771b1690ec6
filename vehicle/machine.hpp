// A wheel loader as data: what a machine file (data/machines/*.json) holds, parsed and checked by
// parse_machine, or filled in by code. WheelLoader builds the multibody model from it, so parsing
// a file and building the model are two steps (as MuJoCo parses a model, then compiles it), and a
// program that embeds talus can make or change a machine without writing JSON.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vehicle/bucket_mesh.hpp"
#include "vehicle/constraint.hpp"
#include "vehicle/ground_contact.hpp"
#include "vehicle/rigid_body.hpp"
#include "vehicle/tyre_contact.hpp"

namespace talus::vehicle {

// a rigid body in the reference pose, axes aligned with the world
struct BodyDescription {
  std::string name;
  double mass = 0.0;            // kg
  Vec3 com = Vec3::Zero();      // m, world, reference pose
  Vec3 inertia = Vec3::Zero();  // kg m^2, principal, about the world axes
};

// the bucket: its body, its profile, where its cutting edge is in the reference pose
struct BucketDescription {
  std::string body;
  BucketGeometry geometry;
  Vec3 tip = Vec3::Zero();    // m, world, reference pose
  double rated_volume = 0.0;  // m^3, heaped (SAE J742), as the maker rates it
};

// a hinge between bodies a and b, optionally with a range of its angle [rad]
struct HingeDescription {
  std::string name, a, b;
  Vec3 point = Vec3::Zero(), axis = Vec3::Zero();  // world, reference pose
  std::optional<std::pair<double, double>> range;
};

// a hydraulic cylinder between pins on bodies a and b; role "lift" (two) or "tilt" (one)
struct CylinderDescription {
  std::string name, a, b, role;
  Vec3 pin_a = Vec3::Zero(), pin_b = Vec3::Zero();  // world, reference pose
  double bore = 0.0, rod = 0.0;                     // m, diameters
  double max_speed = 0.0;                           // m/s
  double length_min = 0.0, length_max = 0.0;        // m, pin to pin, closed and open
};

// the driveline's class data; the gear ratio and stall torque follow from them
struct DrivelineDescription {
  double max_power = 0.0;             // W
  double rated_motor_speed = 0.0;     // rad/s
  double top_speed = 0.0;             // m/s
  double traction_limit = 0.0;        // N
  std::array<std::string, 4> wheels;  // front-left, front-right, rear-left, rear-right bodies
};

struct MachineDescription {
  std::string name;
  // where it came from, for messages: the file's path, or a name given by the code that made it
  std::string source;
  RowParameters joint;  // every joint's compliance and damping time
  double motor_viscous_compliance = 0.0;
  std::vector<BodyDescription> bodies;
  BucketDescription bucket;
  std::vector<HingeDescription> hinges;
  double relief_pressure = 0.0;  // Pa: the cylinders' force range
  std::vector<CylinderDescription> cylinders;
  TyreParameters tyres;
  DrivelineDescription driveline;
  GroundContactParameters bucket_ground;  // the bucket's bottom corners against the ground
};

// the fastest a loader drives and moves a cylinder [m/s]: the largest top speed and cylinder speed
// a machine may declare (check_machine) and the largest target speed an operator's input may ask
// (scenarios and measured runs): loaders' top gear reaches 40 km/h, their cylinders 0.1-0.5 m/s
inline constexpr double kMaxDriveSpeed = 15.0;
inline constexpr double kMaxCylinderSpeed = 1.0;

// the error a description's field raises: "SOURCE: field 'F' PROBLEM; FIX", SOURCE being the file
// or, for a description made by code without one, "machine 'NAME'"
[[noreturn]] void fail_field(const MachineDescription& m, const std::string& field,
                             const std::string& problem, const std::string& fix);

// every value of a description within its physical range (finite; masses, inertias, sizes,
// pressures, speeds, powers, compliances within what wheel loaders have, each range with its unit
// and source in machine.cpp); InputError naming the source (or the machine's name), the field,
// the value and the range. parse_machine and WheelLoader both call it: one check for a file and
// for a description made by code.
void check_machine(const MachineDescription& m);

// the machine file, every value checked for its type and shape, then by check_machine; InputError
// naming the file, the field and the fix. What only the built model can check (names of bodies, a
// cylinder range that holds the reference pose, a possible bucket) WheelLoader checks, naming the
// field.
MachineDescription parse_machine(const std::string& file);

}  // namespace talus::vehicle
