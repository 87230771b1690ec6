// The wheel loader (SPEC §2.4, paper §4.2), built from one data file (data/machines/*.json):
// 10 rigid bodies, 10 hinges, 3 cylinders (prismatic pairs pinned at both ends, with linear motors
// and stroke limits), the driveline (engine hinge motor with a speed-dependent torque limit, open
// differentials, rigid transfer case) and four tyre contacts on flat ground.
// Controls are target speeds: drive [m/s], lift and tilt cylinders [m/s], clipped to the data file's
// maxima. The bucket is exposed for a later particle coupling: bucket_body(), set_bucket_wrench()
// and bucket_mobility() (the articulated 6x6 mobility from the direct solver's factor).
#pragma once
#include <array>
#include <memory>
#include <string>

#include "vehicle/bucket_mesh.hpp"
#include "vehicle/driveline.hpp"
#include "vehicle/ground_contact.hpp"
#include "vehicle/joints.hpp"
#include "vehicle/machine.hpp"
#include "vehicle/multibody.hpp"
#include "vehicle/scenario.hpp"
#include "vehicle/tyre_contact.hpp"

namespace talus::vehicle {

struct CylinderSpec {
  double force_push = 0.0;   // N, relief pressure x piston area
  double force_pull = 0.0;   // N, relief pressure x annulus area
  double max_speed = 0.0;    // m/s
  double length_min = 0.0, length_max = 0.0;  // m
  double piston_area = 0.0;  // m^2, bore side: the oil an extending cylinder takes per metre
  double annulus_area = 0.0; // m^2, rod side: the oil a retracting cylinder takes per metre
};

class WheelLoader {
 public:
  // build from a machine (vehicle/machine.hpp: parsed from a file or made by code); payload_kg is
  // a point mass at the bucket's struck-volume centroid (a loaded bucket without particles).
  // InputError naming the description's source and field for what does not fit together
  explicit WheelLoader(const MachineDescription& machine, double payload_kg = 0.0);
  // the same from a machine data file (parse_machine, then build)
  explicit WheelLoader(const std::string& machine_file, double payload_kg = 0.0);

  MultibodySystem& system() { return system_; }
  const MultibodySystem& system() const { return system_; }
  const std::vector<RigidBody>& bodies() const { return system_.bodies(); }

  // feedforward controls (target speeds; clipped to the machine's limits)
  void set_drive_speed(double v);
  void set_lift_speed(double v);
  void set_tilt_speed(double v);
  // the engine power the driveline may use from the next step on [W] (> 0; max_power() by
  // default): the model extensions that share the engine with the hydraulics lower it
  void set_drive_power_limit(double watts) { driveline_->set_power_limit(watts); }
  void step(double h) { system_.step(h); }

  // coupling hooks
  int bucket_body() const { return bucket_; }
  void set_bucket_wrench(const Vec6& wrench) { system_.set_external_wrench(bucket_, wrench); }
  Mat6 bucket_mobility() const { return system_.mobility(bucket_); }
  // bucket mesh (profile frame) and the pose that places it: world = body pose * profile_to_body
  const BucketMesh& bucket_mesh() const { return mesh_; }
  Vec3 bucket_mesh_vertex_world(int i) const;
  Vec3 bucket_tip_world() const;
  // where the payload sits: the bucket's struck-volume centroid, world frame, current pose
  Vec3 payload_point_world() const;

  // static stability straight ahead, in the current pose: the payload [kg] at the bucket's
  // volume centroid at which the rear tyres carry nothing, i.e. the machine turns over its front
  // tyres' contact line (flat ground, gravity only, bucket clear of the ground; the payload the
  // machine carries now counts towards it). Measured with the boom at its longest reach and the
  // bucket curled this is the static tipping load of ISO 14397-1 (docs/vehicle.md)
  double static_tipping_load() const;

  // parts, for sensors and tests
  const std::array<CylinderJoint*, 2>& lift_cylinders() const { return lift_; }
  CylinderJoint& tilt_cylinder() const { return *tilt_; }
  const Driveline& driveline() const { return *driveline_; }
  const std::array<TyreContact*, 4>& tyres() const { return tyres_; }
  // the bucket's bottom corners (cutting-edge and heel ends) against the flat ground
  const PointGroundContact& bucket_ground() const { return *bucket_ground_; }
  // rigid walls for the bucket (a pile's container): each a contact of the bucket's hull (its
  // mesh's vertices) with the plane, rows for the kWallPoints of them nearest the wall, with the
  // machine's bucket_ground parameters (the same steel on the same gravel-covered rigid surface).
  // Named "bucket_wall_0", "bucket_wall_1", ... in the order given; add them before the
  // system's first step that should see them. Only the bucket meets them: it leads the machine
  // into a pile (the tyres and frame stay behind it on the straight paths of the scenarios)
  void add_bucket_walls(const std::vector<RigidPlane>& walls);
  const std::vector<PointGroundContact*>& bucket_walls() const { return bucket_walls_; }
  // rows per wall: the four hull vertices nearest it, a face when one lies flat against the wall
  // (the curled bucket's bottom: tip and heel ends), two points of an edge when the bucket meets
  // it edge first. The walls are planes without end, as the particles' are: a bucket lifted above
  // a real wall's top would pass over it, here it cannot
  static constexpr int kWallPoints = 4;
  const CylinderSpec& lift_spec() const { return lift_spec_; }
  const CylinderSpec& tilt_spec() const { return tilt_spec_; }
  HingeJoint& hinge(const std::string& name) const;
  std::vector<Joint*> joints() const { return joints_; }
  int front_frame() const { return front_frame_; }
  int body(const std::string& name) const { return system_.body_index(name); }
  double operating_mass() const;  // kg, all bodies (payload included)
  double payload() const { return payload_; }
  double top_speed() const { return top_speed_; }
  double traction_limit() const { return traction_limit_; }
  double max_power() const { return driveline_->parameters().max_power; }
  double rated_bucket_volume() const { return rated_volume_; }
  const std::string& name() const { return name_; }

 private:
  // the stages of the constructor, in order; body_of fails naming the field when no body has
  // the name
  int body_of(const MachineDescription& m, const std::string& name, const std::string& field) const;
  void add_bodies(const MachineDescription& m);  // and the loaded bucket
  std::vector<std::pair<int, int>> add_hinges(const MachineDescription& m);  // each one's (a, b)
  void add_cylinders(const MachineDescription& m);
  void add_driveline(const MachineDescription& m,
                     const std::vector<std::pair<int, int>>& hinge_bodies);

  MultibodySystem system_;
  std::string name_;
  std::array<CylinderJoint*, 2> lift_{};
  CylinderJoint* tilt_ = nullptr;
  Driveline* driveline_ = nullptr;
  std::array<TyreContact*, 4> tyres_{};
  PointGroundContact* bucket_ground_ = nullptr;
  std::vector<PointGroundContact*> bucket_walls_;
  GroundContactParameters bucket_contact_;  // the machine file's bucket_ground
  std::vector<Joint*> joints_;
  std::vector<std::pair<std::string, HingeJoint*>> hinges_;
  CylinderSpec lift_spec_, tilt_spec_;
  BucketMesh mesh_;
  Vec3 tip_local_ = Vec3::Zero();           // cutting-edge tip in bucket body coordinates
  Eigen::Isometry3d profile_to_body_ = Eigen::Isometry3d::Identity();
  int bucket_ = -1, front_frame_ = -1;
  double payload_ = 0.0, top_speed_ = 0.0, traction_limit_ = 0.0, rated_volume_ = 0.0;
};

// a vehicle-only scenario's payload that `loaded` (the scenario's machine carrying it) cannot hold
// on its wheels even with its boom low, its shortest reach: InputError naming the scenario's file
// and field 'payload'. 1e12 kg ran to the end with the machine at 90 degrees of pitch; the library
// itself builds such a machine for test rigs that hold its frame, so runs check, not the machine
void check_payload_holds(const Scenario& scenario, const WheelLoader& loaded);

// the straight static tipping load of the empty machine at its farthest reach [kg], the pose ISO
// 14397-1 rates a loader in: posed by its own joints (bucket curled as it carries, boom lifted
// until the line from the boom pivot to the bucket hinge is level, then at rest), the payload the
// moment balance about the front wheels says tips it. Costs about 2,700 steps of the machine alone
double full_reach_tipping_load(const MachineDescription& m);

// a warning for a payload above the machine's rated operating load (ISO 14397-1: half the tipping
// load; here half the straight one at full reach, so an upper estimate), or "" below it. Such a
// payload runs, but the machine may tip forward when it brakes or lowers with the boom up
// (docs/vehicle.md: load-carry pitches to -12 deg with 7 t and to -41 deg with 9 t)
std::string payload_warning(const Scenario& scenario, const MachineDescription& m);

}  // namespace talus::vehicle
