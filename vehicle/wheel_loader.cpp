#include "vehicle/wheel_loader.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "host/error.hpp"
#include "vehicle/sensors.hpp"

namespace talus::vehicle {

WheelLoader::WheelLoader(const std::string& machine_file, double payload_kg)
    : WheelLoader(parse_machine(machine_file), payload_kg) {}

WheelLoader::WheelLoader(const MachineDescription& m, double payload_kg) : payload_(payload_kg) {
  if (!(payload_kg >= 0.0))
    throw InputError("payload must be >= 0 kg (got " + std::to_string(payload_kg) + ")");
  name_ = m.name;
  check_machine(m);
  // the parts in an order that joints can take their anchors from: bodies and the loaded bucket,
  // hinges, cylinders, then the wheels' tyres, the bucket's ground contact and the driveline
  add_bodies(m);
  const std::vector<std::pair<int, int>> hinge_bodies = add_hinges(m);
  add_cylinders(m);
  add_driveline(m, hinge_bodies);
}

int WheelLoader::body_of(const MachineDescription& m, const std::string& name,
                         const std::string& field) const {
  for (int i = 0; i < static_cast<int>(system_.bodies().size()); ++i) {
    if (system_.body(i).name == name) return i;
  }
  fail_field(m, field, "names no body ('" + name + "')", "use one of the names in 'bodies'");
}

void WheelLoader::add_bodies(const MachineDescription& m) {
  // bodies in the reference pose, axes aligned with the world
  for (const BodyDescription& d : m.bodies) {
    RigidBody b;
    b.name = d.name;
    b.mass = d.mass;
    b.position = d.com;
    b.inertia = d.inertia.asDiagonal();
    system_.add_body(b);
  }

  // bucket geometry and payload (merged into the bucket before joints take local anchors)
  bucket_ = body_of(m, m.bucket.body, "bucket.body");
  rated_volume_ = m.bucket.rated_volume;
  try {
    mesh_ = make_bucket_mesh(m.bucket.geometry);
  } catch (const InputError&) {
    throw;
  } catch (const Error& e) {
    fail_field(m, "bucket", std::string("describes an impossible bucket (") + e.what() + ")",
               "correct its dimensions");
  }
  const Vec3& tip_world = m.bucket.tip;
  // the profile frame is world-aligned at the tip in the reference pose
  profile_to_body_ = Eigen::Isometry3d::Identity();
  profile_to_body_.translation() = system_.body(bucket_).point_to_local(tip_world);
  add_point_mass(system_.body(bucket_), payload_, tip_world + mesh_.volume_centroid);
  // the body's centre of mass moved with the payload: the profile frame stays put in the world
  profile_to_body_.translation() = system_.body(bucket_).point_to_local(tip_world);
  tip_local_ = profile_to_body_.translation();
}

std::vector<std::pair<int, int>> WheelLoader::add_hinges(const MachineDescription& m) {
  // each hinge's bodies (a, b), for the wheels' frames
  // hinges
  std::vector<std::pair<int, int>> hinge_bodies;
  for (size_t i = 0; i < m.hinges.size(); ++i) {
    const HingeDescription& d = m.hinges[i];
    const std::string where = "hinges[" + std::to_string(i) + "]";
    const int a = body_of(m, d.a, where + ".a");
    const int b = body_of(m, d.b, where + ".b");
    auto& h = system_.add_constraint(
        std::make_unique<HingeJoint>(system_.bodies(), a, b, d.point, d.axis, m.joint));
    h.name = d.name;
    if (d.range) {
      h.range.enabled = true;
      h.range.lower = d.range->first;
      h.range.upper = d.range->second;
    }
    hinges_.emplace_back(h.name, &h);
    joints_.push_back(&h);
    hinge_bodies.emplace_back(a, b);
  }
  return hinge_bodies;
}

void WheelLoader::add_cylinders(const MachineDescription& m) {
  // cylinders: linear motors with force range from relief pressure, and stroke limits
  const double pressure = m.relief_pressure;
  int lifts = 0;
  for (size_t i = 0; i < m.cylinders.size(); ++i) {
    const CylinderDescription& d = m.cylinders[i];
    const std::string where = "cylinders[" + std::to_string(i) + "]";
    const int a = body_of(m, d.a, where + ".a");
    const int b = body_of(m, d.b, where + ".b");
    auto& cyl = system_.add_constraint(
        std::make_unique<CylinderJoint>(system_.bodies(), a, d.pin_a, b, d.pin_b, m.joint));
    cyl.name = d.name;
    CylinderSpec s;
    s.force_push = pressure * M_PI / 4 * d.bore * d.bore;
    s.force_pull = pressure * M_PI / 4 * (d.bore * d.bore - d.rod * d.rod);
    s.piston_area = M_PI / 4 * d.bore * d.bore;
    s.annulus_area = M_PI / 4 * (d.bore * d.bore - d.rod * d.rod);
    s.max_speed = d.max_speed;
    s.length_min = d.length_min;
    s.length_max = d.length_max;
    const double now = cyl.coordinate(system_.bodies());
    if (!(s.length_min <= now && now <= s.length_max)) {
      fail_field(m, where + ".length_range",
                 "does not contain the reference-pose length " + std::to_string(now) + " m",
                 "widen the range or move the pins");
    }
    cyl.range.enabled = true;
    cyl.range.lower = s.length_min;
    cyl.range.upper = s.length_max;
    cyl.motor.enabled = true;
    cyl.motor.force_min = -s.force_pull;
    cyl.motor.force_max = s.force_push;
    cyl.motor.viscous_compliance = m.motor_viscous_compliance;
    if (d.role == "lift") {
      if (lifts >= 2)
        fail_field(m, where + ".role", "is a third lift cylinder",
                   "the model has two lift cylinders");
      lift_[lifts++] = &cyl;
      lift_spec_ = s;
    } else if (d.role == "tilt") {
      if (tilt_)
        fail_field(m, where + ".role", "is a second tilt cylinder",
                   "the model has one tilt cylinder");
      tilt_ = &cyl;
      tilt_spec_ = s;
    } else {
      fail_field(m, where + ".role", "is '" + d.role + "'", "use \"lift\" or \"tilt\"");
    }
    joints_.push_back(&cyl);
  }
  if (lifts != 2 || !tilt_)
    fail_field(m, "cylinders", "needs two lift and one tilt cylinder", "add the missing cylinders");
}

void WheelLoader::add_driveline(const MachineDescription& m,
                                const std::vector<std::pair<int, int>>& hinge_bodies) {
  // driveline: gear ratio from rated speed and top speed, stall torque from the traction limit
  const TyreParameters& tp = m.tyres;
  DrivelineParameters dp;
  dp.max_power = m.driveline.max_power;
  top_speed_ = m.driveline.top_speed;
  traction_limit_ = m.driveline.traction_limit;
  dp.wheel_radius = tp.radius;
  dp.gear_ratio = m.driveline.rated_motor_speed * tp.radius / top_speed_;
  dp.stall_torque = traction_limit_ * tp.radius / dp.gear_ratio;
  dp.max_speed = top_speed_;
  dp.viscous_compliance = m.motor_viscous_compliance;
  std::array<int, 4> w{}, frames{};
  for (int i = 0; i < 4; ++i) {
    w[i] = body_of(m, m.driveline.wheels[i], "driveline.wheels.wheel");
    // the frame a wheel turns in is the other body of its hinge
    frames[i] = kWorld;
    for (const auto& [a, b] : hinge_bodies)
      if (b == w[i]) frames[i] = a;
    if (frames[i] == kWorld)
      fail_field(m, "driveline.wheels", "names a wheel without an axle hinge",
                 "add its hinge as b");
    tyres_[i] = &system_.add_constraint(std::make_unique<TyreContact>(w[i], Vec3::UnitY(), tp));
    tyres_[i]->name = "tyre_" + system_.body(w[i]).name;
  }
  // the bucket's bottom corners on the ground: both ends of the cutting edge and of the heel
  // (where the flat bottom meets the corner arc), in the bucket body's frame
  std::vector<Vec3> corners;
  for (const Vec3& c : bottom_corners(mesh_)) corners.push_back(profile_to_body_ * c);
  bucket_ground_ = &system_.add_constraint(
      std::make_unique<PointGroundContact>(bucket_, corners, m.bucket_ground));
  bucket_ground_->name = "bucket_ground";
  bucket_contact_ = m.bucket_ground;
  driveline_ = &system_.add_constraint(std::make_unique<Driveline>(w, frames, Vec3::UnitY(), dp));
  driveline_->name = "driveline";
  front_frame_ = frames[0];
}

void WheelLoader::set_drive_speed(double v) { driveline_->set_target_drive_speed(std::clamp(v, -top_speed_, top_speed_)); }

void WheelLoader::set_lift_speed(double v) {
  const double s = std::clamp(v, -lift_spec_.max_speed, lift_spec_.max_speed);
  for (auto* c : lift_) c->motor.target_speed = s;
}

void WheelLoader::set_tilt_speed(double v) {
  tilt_->motor.target_speed = std::clamp(v, -tilt_spec_.max_speed, tilt_spec_.max_speed);
}

HingeJoint& WheelLoader::hinge(const std::string& name) const {
  for (const auto& [n, h] : hinges_) {
    if (n == name) return *h;
  }
  throw Error("wheel loader: no hinge named '" + name + "'");
}

Vec3 WheelLoader::bucket_mesh_vertex_world(int i) const {
  return system_.body(bucket_).point_to_world(profile_to_body_ * mesh_.vertices.at(i));
}

void WheelLoader::add_bucket_walls(const std::vector<RigidPlane>& walls) {
  // the hull's candidates: every vertex of the bucket's mesh, in the bucket body's frame
  std::vector<Vec3> hull;
  hull.reserve(mesh_.vertices.size());
  for (const Vec3& v : mesh_.vertices) hull.push_back(profile_to_body_ * v);
  for (const RigidPlane& wall : walls) {
    auto& c = system_.add_constraint(
        std::make_unique<PointGroundContact>(bucket_, hull, bucket_contact_, wall, kWallPoints));
    c.name = "bucket_wall_" + std::to_string(bucket_walls_.size());
    bucket_walls_.push_back(&c);
  }
}

Vec3 WheelLoader::bucket_tip_world() const { return system_.body(bucket_).point_to_world(tip_local_); }

Vec3 WheelLoader::payload_point_world() const {
  return system_.body(bucket_).point_to_world(profile_to_body_ * mesh_.volume_centroid);
}

double WheelLoader::static_tipping_load() const {
  // the tipping line: under the front wheels' centres (tyres_[0..1] are the front pair)
  const double x_line = 0.5 * (system_.body(tyres_[0]->wheel()).position.x() +
                               system_.body(tyres_[1]->wheel()).position.x());
  // the weight's moment about it [kg m], positive forward (the payload now carried included)
  double moment = 0.0;
  for (const auto& b : system_.bodies()) moment += b.mass * (b.position.x() - x_line);
  // the payload that brings the moment to zero, added to what the bucket already carries
  const double arm = payload_point_world().x() - x_line;
  if (!(arm > 0.0)) return std::numeric_limits<double>::infinity();  // load behind the line: no tipping
  return payload_ - moment / arm;
}

double WheelLoader::operating_mass() const {
  double m = 0.0;
  for (const auto& b : system_.bodies()) m += b.mass;
  return m;
}

void check_payload_holds(const Scenario& scenario, const WheelLoader& loaded) {
  const double tipping = loaded.static_tipping_load();
  if (scenario.payload > tipping) {
    std::ostringstream msg;
    msg << scenario.path << ": field 'payload': " << scenario.payload
        << " kg is above the static tipping load of " << loaded.name() << " with its boom low ("
        << std::lround(tipping)
        << " kg): it would tip forward onto its bucket; give a payload below that";
    throw InputError(msg.str());
  }
}

double full_reach_tipping_load(const MachineDescription& m) {
  WheelLoader w(m);
  // the scenarios' timestep [s] and the speeds of the pose [m/s], slow enough to arrive at rest
  constexpr double kStep = 0.005, kCurlSpeed = 0.15, kLiftSpeed = 0.1;
  const auto hold = [&](double seconds, double lift, double tilt) {
    w.set_lift_speed(lift);
    w.set_tilt_speed(tilt);
    for (int k = 0; k < static_cast<int>(std::lround(seconds / kStep)); ++k) w.step(kStep);
  };
  // settle on the tyres, curl the bucket as it carries, lift until the boom is level (its reach is
  // longest there) or the stroke ends, then come to rest
  hold(0.2, 0.0, 0.0);
  hold(0.9, 0.0, kCurlSpeed);
  // the whole stroke at the speed the cylinders reach (set_lift_speed clamps to their top), twice
  const double speed = std::min(kLiftSpeed, w.lift_spec().max_speed);
  const double longest_lift = 2.0 * (w.lift_spec().length_max - w.lift_spec().length_min) / speed;
  w.set_lift_speed(kLiftSpeed);
  w.set_tilt_speed(0.0);
  const int longest = static_cast<int>(std::lround(longest_lift / kStep));
  for (int k = 0; k < longest && read_sensors(w, 0.0).boom_deg < 0.0; ++k) w.step(kStep);
  hold(3.0, 0.0, 0.0);
  return w.static_tipping_load();
}

std::string payload_warning(const Scenario& scenario, const MachineDescription& m) {
  if (scenario.payload <= 0.0) return "";
  const double tipping = full_reach_tipping_load(m);
  const double rated = 0.5 * tipping;
  if (scenario.payload <= rated) return "";
  std::ostringstream msg;
  msg << scenario.path << ": payload " << std::lround(scenario.payload)
      << " kg is above the rated operating load of " << m.name << " (" << std::lround(rated)
      << " kg: half its static tipping load at full reach, " << std::lround(tipping)
      << " kg, ISO 14397-1); it runs, but the machine may tip forward when it brakes or lowers "
         "with the boom up";
  return msg.str();
}

}  // namespace talus::vehicle
