#include "vehicle/wheel_loader.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "host/error.hpp"
#include "vehicle/data_file.hpp"

namespace talus::vehicle {

WheelLoader::WheelLoader(const std::string& machine_file, double payload_kg) : payload_(payload_kg) {
  const DataFile f(machine_file);
  const auto& root = f.root();
  if (!(payload_kg >= 0.0)) throw InputError("payload must be >= 0 kg (got " + std::to_string(payload_kg) + ")");
  name_ = f.text(root, "", "name");

  // solver parameters shared by all joints
  const auto& solver = f.member(root, "", "solver");
  RowParameters joint;
  joint.compliance = f.number(solver, "solver", "joint_compliance");
  joint.damping_time = f.number(solver, "solver", "joint_damping_time");
  const double motor_compliance = f.number(solver, "solver", "motor_viscous_compliance");
  if (joint.compliance < 0 || joint.damping_time < 0 || motor_compliance < 0) {
    f.fail("solver", "has a negative compliance or damping time", "use values >= 0");
  }

  // bodies in the reference pose, axes aligned with the world
  const auto& bodies = f.member(root, "", "bodies");
  if (!bodies.is_array() || bodies.empty()) f.fail("bodies", "is not a non-empty array", "list the rigid bodies");
  for (size_t i = 0; i < bodies.size(); ++i) {
    const std::string where = "bodies[" + std::to_string(i) + "]";
    RigidBody b;
    b.name = f.text(bodies[i], where, "name");
    b.mass = f.number(bodies[i], where, "mass");
    b.position = f.vec3(bodies[i], where, "com");
    const Vec3 inertia = f.vec3(bodies[i], where, "inertia");
    if (!(b.mass > 0) || !(inertia.minCoeff() > 0)) f.fail(where, "has a mass or inertia <= 0", "give positive values");
    b.inertia = inertia.asDiagonal();
    system_.add_body(b);
  }
  auto body_of = [&](const nlohmann::json& j, const std::string& where, const std::string& key) {
    const std::string n = f.text(j, where, key);
    for (int i = 0; i < static_cast<int>(system_.bodies().size()); ++i) {
      if (system_.body(i).name == n) return i;
    }
    f.fail(where + "." + key, "names no body ('" + n + "')", "use one of the names in 'bodies'");
  };

  // bucket geometry and payload (merged into the bucket before joints take local anchors)
  const auto& bk = f.member(root, "", "bucket");
  bucket_ = body_of(bk, "bucket", "body");
  BucketGeometry g;
  g.width = f.number(bk, "bucket", "width");
  g.side_plate = f.number(bk, "bucket", "side_plate");
  g.bottom_length = f.number(bk, "bucket", "bottom_length");
  g.corner_radius = f.number(bk, "bucket", "corner_radius");
  g.back_height = f.number(bk, "bucket", "back_height");
  g.edge_length = f.number(bk, "bucket", "edge_length");
  const auto& lip = f.quantity(bk, "bucket", "lip");
  if (!lip.is_array() || lip.size() != 2 || !lip[0].is_number() || !lip[1].is_number()) {
    f.fail("bucket.lip.value", "is not two numbers", "give [x, z] of the top lip relative to the cutting edge");
  }
  g.lip = Vec3(lip[0].get<double>(), 0.0, lip[1].get<double>());
  rated_volume_ = f.number(bk, "bucket", "rated_volume");
  try {
    mesh_ = make_bucket_mesh(g);
  } catch (const InputError&) {
    throw;
  } catch (const Error& e) {
    f.fail("bucket", std::string("describes an impossible bucket (") + e.what() + ")", "correct its dimensions");
  }
  const Vec3 tip_world = f.vec3(bk, "bucket", "tip");
  // the profile frame is world-aligned at the tip in the reference pose
  profile_to_body_ = Eigen::Isometry3d::Identity();
  profile_to_body_.translation() = system_.body(bucket_).point_to_local(tip_world);
  add_point_mass(system_.body(bucket_), payload_kg, tip_world + mesh_.volume_centroid);
  // the body's centre of mass moved with the payload: the profile frame stays put in the world
  profile_to_body_.translation() = system_.body(bucket_).point_to_local(tip_world);
  tip_local_ = profile_to_body_.translation();

  // hinges
  const auto& hinges = f.member(root, "", "hinges");
  if (!hinges.is_array()) f.fail("hinges", "is not an array", "list the hinge joints");
  for (size_t i = 0; i < hinges.size(); ++i) {
    const std::string where = "hinges[" + std::to_string(i) + "]";
    const int a = body_of(hinges[i], where, "a");
    const int b = body_of(hinges[i], where, "b");
    const Vec3 axis = f.vec3(hinges[i], where, "axis");
    if (axis.norm() < 1e-9) f.fail(where + ".axis", "is zero", "give a direction");
    auto& h = system_.add_constraint(
        std::make_unique<HingeJoint>(system_.bodies(), a, b, f.vec3(hinges[i], where, "point"), axis, joint));
    h.name = f.text(hinges[i], where, "name");
    if (hinges[i].contains("range")) {
      const auto& r = f.quantity(hinges[i], where, "range");
      if (!r.is_array() || r.size() != 2 || !r[0].is_number() || !r[1].is_number() || r[0].get<double>() > r[1].get<double>()) {
        f.fail(where + ".range.value", "is not [lower, upper] with lower <= upper", "give two angles in rad");
      }
      h.range.enabled = true;
      h.range.lower = r[0].get<double>();
      h.range.upper = r[1].get<double>();
    }
    hinges_.emplace_back(h.name, &h);
    joints_.push_back(&h);
  }

  // cylinders: linear motors with force range from relief pressure, and stroke limits
  const double pressure = f.number(f.member(root, "", "hydraulics"), "hydraulics", "relief_pressure");
  const auto& cylinders = f.member(root, "", "cylinders");
  int lifts = 0;
  for (size_t i = 0; i < cylinders.size(); ++i) {
    const std::string where = "cylinders[" + std::to_string(i) + "]";
    const auto& c = cylinders[i];
    const int a = body_of(c, where, "a");
    const int b = body_of(c, where, "b");
    auto& cyl = system_.add_constraint(std::make_unique<CylinderJoint>(system_.bodies(), a, f.vec3(c, where, "pin_a"), b,
                                                                       f.vec3(c, where, "pin_b"), joint));
    cyl.name = f.text(c, where, "name");
    const double bore = f.number(c, where, "bore");
    const double rod = f.number(c, where, "rod");
    if (!(bore > rod) || !(rod > 0)) f.fail(where, "has bore <= rod or rod <= 0", "give bore > rod > 0 in metres");
    CylinderSpec s;
    s.force_push = pressure * M_PI / 4 * bore * bore;
    s.force_pull = pressure * M_PI / 4 * (bore * bore - rod * rod);
    s.piston_area = M_PI / 4 * bore * bore;
    s.annulus_area = M_PI / 4 * (bore * bore - rod * rod);
    s.max_speed = f.number(c, where, "max_speed");
    const auto& range = f.quantity(c, where, "length_range");
    if (!range.is_array() || range.size() != 2 || !range[0].is_number() || !range[1].is_number()) {
      f.fail(where + ".length_range.value", "is not [min, max]", "give the closed and open pin-to-pin lengths in m");
    }
    s.length_min = range[0].get<double>();
    s.length_max = range[1].get<double>();
    const double now = cyl.coordinate(system_.bodies());
    if (!(s.length_min <= now && now <= s.length_max)) {
      f.fail(where + ".length_range", "does not contain the reference-pose length " + std::to_string(now) + " m",
             "widen the range or move the pins");
    }
    cyl.range.enabled = true;
    cyl.range.lower = s.length_min;
    cyl.range.upper = s.length_max;
    cyl.motor.enabled = true;
    cyl.motor.force_min = -s.force_pull;
    cyl.motor.force_max = s.force_push;
    cyl.motor.viscous_compliance = motor_compliance;
    const std::string role = f.text(c, where, "role");
    if (role == "lift") {
      if (lifts >= 2) f.fail(where + ".role", "is a third lift cylinder", "the model has two lift cylinders");
      lift_[lifts++] = &cyl;
      lift_spec_ = s;
    } else if (role == "tilt") {
      if (tilt_) f.fail(where + ".role", "is a second tilt cylinder", "the model has one tilt cylinder");
      tilt_ = &cyl;
      tilt_spec_ = s;
    } else {
      f.fail(where + ".role", "is '" + role + "'", "use \"lift\" or \"tilt\"");
    }
    joints_.push_back(&cyl);
  }
  if (lifts != 2 || !tilt_) f.fail("cylinders", "needs two lift and one tilt cylinder", "add the missing cylinders");

  // tyres
  const auto& ty = f.member(root, "", "tyres");
  TyreParameters tp;
  tp.radius = f.number(ty, "tyres", "radius");
  tp.width = f.number(ty, "tyres", "width");
  tp.elastic_modulus = f.number(ty, "tyres", "elastic_modulus");
  tp.friction = f.number(ty, "tyres", "friction");
  tp.damping_time = f.number(ty, "tyres", "damping_time");
  tp.viscous_compliance = f.number(ty, "tyres", "friction_viscous_compliance");
  if (!(tp.radius > 0) || !(tp.width > 0) || !(tp.elastic_modulus > 0) || !(tp.friction >= 0)) {
    f.fail("tyres", "has a non-positive size, modulus or a negative friction", "correct the values");
  }

  // driveline: gear ratio from rated speed and top speed, stall torque from the traction limit
  const auto& dl = f.member(root, "", "driveline");
  DrivelineParameters dp;
  dp.max_power = f.number(dl, "driveline", "max_power");
  const double rated = f.number(dl, "driveline", "rated_motor_speed");
  top_speed_ = f.number(dl, "driveline", "top_speed");
  traction_limit_ = f.number(dl, "driveline", "traction_limit");
  if (!(dp.max_power > 0) || !(rated > 0) || !(top_speed_ > 0) || !(traction_limit_ > 0)) {
    f.fail("driveline", "has a value <= 0", "give positive power, speeds and traction");
  }
  dp.wheel_radius = tp.radius;
  dp.gear_ratio = rated * tp.radius / top_speed_;
  dp.stall_torque = traction_limit_ * tp.radius / dp.gear_ratio;
  dp.max_speed = top_speed_;
  dp.viscous_compliance = motor_compliance;
  const auto& wheels = f.quantity(dl, "driveline", "wheels");
  if (!wheels.is_array() || wheels.size() != 4) f.fail("driveline.wheels.value", "is not four names", "list FL, FR, RL, RR");
  std::array<int, 4> w{}, frames{};
  for (int i = 0; i < 4; ++i) {
    if (!wheels[i].is_string()) f.fail("driveline.wheels.value", "has a non-string entry", "list body names");
    const nlohmann::json holder = {{"wheel", wheels[i]}};
    w[i] = body_of(holder, "driveline.wheels", "wheel");
    // the frame a wheel turns in is the other body of its hinge
    frames[i] = kWorld;
    for (size_t k = 0; k < hinges.size(); ++k) {
      const std::string hw = "hinges[" + std::to_string(k) + "]";
      if (body_of(hinges[k], hw, "b") == w[i]) frames[i] = body_of(hinges[k], hw, "a");
    }
    if (frames[i] == kWorld) f.fail("driveline.wheels", "names a wheel without an axle hinge", "add its hinge as b");
    tyres_[i] = &system_.add_constraint(std::make_unique<TyreContact>(w[i], Vec3::UnitY(), tp));
    tyres_[i]->name = "tyre_" + system_.body(w[i]).name;
  }
  // the bucket's bottom corners on the ground: both ends of the cutting edge and of the heel
  // (where the flat bottom meets the corner arc), in the bucket body's frame
  const auto& bg = f.member(root, "", "bucket_ground");
  GroundContactParameters gp;
  gp.stiffness = f.number(bg, "bucket_ground", "stiffness");
  gp.friction = f.number(bg, "bucket_ground", "friction");
  gp.damping_time = f.number(bg, "bucket_ground", "damping_time");
  gp.viscous_compliance = f.number(bg, "bucket_ground", "friction_viscous_compliance");
  if (!(gp.stiffness > 0) || !(gp.friction >= 0) || !(gp.damping_time >= 0) || !(gp.viscous_compliance >= 0))
    f.fail("bucket_ground", "has a non-positive stiffness or a negative friction or damping", "correct the values");
  std::vector<Vec3> corners;
  const double half_width = 0.5 * mesh_.inner_width;
  for (double x : {0.0, -g.bottom_length})
    for (double y : {-half_width, half_width}) corners.push_back(profile_to_body_ * Vec3(x, y, 0.0));
  bucket_ground_ = &system_.add_constraint(std::make_unique<PointGroundContact>(bucket_, corners, gp));
  bucket_ground_->name = "bucket_ground";
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

}  // namespace talus::vehicle
