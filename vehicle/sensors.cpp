#include "vehicle/sensors.hpp"

#include <cmath>
#include <ostream>

namespace talus::vehicle {

namespace {

double degrees(double rad) { return rad * 180.0 / M_PI; }

// angle of a world direction in the x-z plane of a frame, positive towards +z
double plane_angle(const RigidBody& frame, const Vec3& world_direction) {
  const Vec3 d = frame.vector_to_local(world_direction);
  return std::atan2(d.z(), d.x());
}

}  // namespace

SensorSample read_sensors(const WheelLoader& loader, double t) {
  const auto& bodies = loader.bodies();
  SensorSample s;
  s.t = t;
  // cylinder forces: motor plus stroke-limit force, which the pressure sensors would also see
  for (const auto* c : loader.lift_cylinders()) {
    s.f_lift += c->actuator_force();
    s.d_lift += 0.5 * (c->coordinate(bodies) - loader.lift_spec().length_min);
    s.lift_rate += 0.5 * c->coordinate_rate(bodies);
  }
  s.f_tilt = loader.tilt_cylinder().actuator_force();
  s.d_tilt = loader.tilt_cylinder().coordinate(bodies) - loader.tilt_spec().length_min;
  s.tilt_rate = loader.tilt_cylinder().coordinate_rate(bodies);
  // traction: ground friction on the wheels along their heading; speed from wheel revolution
  for (const auto* ty : loader.tyres()) s.f_traction += ty->longitudinal_force();
  s.v_drive = loader.driveline().drive_speed(bodies);
  // angles in the front frame: boom line pivot -> bucket hinge, bucket bottom plate, pitch
  const RigidBody& frame = bodies[loader.front_frame()];
  const auto& pivot = loader.hinge("boom_pivot");
  const auto& hinge = loader.hinge("bucket_hinge");
  const Vec3 boom = hinge.frame_a().world_anchor(bodies) - pivot.frame_a().world_anchor(bodies);
  s.boom_deg = degrees(plane_angle(frame, boom));
  s.bucket_deg = degrees(plane_angle(frame, bodies[loader.bucket_body()].vector_to_world(Vec3::UnitX())));
  const Vec3 x = frame.vector_to_world(Vec3::UnitX());
  s.pitch_deg = degrees(std::atan2(x.z(), std::hypot(x.x(), x.y())));
  // position: front axle centre; bucket tip
  const auto& tyres = loader.tyres();
  s.x_vehicle = 0.5 * (bodies[tyres[0]->wheel()].position.x() + bodies[tyres[1]->wheel()].position.x());
  const Vec3 tip = loader.bucket_tip_world();
  s.bucket_tip_x = tip.x();
  s.bucket_tip_z = tip.z();
  s.power = s.f_traction * s.v_drive + s.f_lift * s.lift_rate + s.f_tilt * s.tilt_rate;
  return s;
}

const char* sensor_csv_header() {
  return "t,f_lift,f_tilt,f_traction,v_drive,d_lift,d_tilt,boom_deg,bucket_deg,pitch_deg,x_vehicle,"
         "bucket_tip_x,bucket_tip_z,power";
}

void write_sensor_csv_row(std::ostream& out, const SensorSample& s) {
  out << s.t << ',' << s.f_lift << ',' << s.f_tilt << ',' << s.f_traction << ',' << s.v_drive << ',' << s.d_lift
      << ',' << s.d_tilt << ',' << s.boom_deg << ',' << s.bucket_deg << ',' << s.pitch_deg << ',' << s.x_vehicle
      << ',' << s.bucket_tip_x << ',' << s.bucket_tip_z << ',' << s.power << '\n';
}

void SensorLog::after_step(const WheelLoader& loader, double t, double h) {
  const SensorSample s = read_sensors(loader, t);
  work_ += s.power * h;
  // sample at t = k period (within half a step)
  const double next = static_cast<double>(samples_.size()) * period_;
  if (t + 0.5 * h >= next) samples_.push_back(s);
}

}  // namespace talus::vehicle
