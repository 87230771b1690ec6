// The aggregate body of the type-G terrain (issue 14, paper §4.4; Servin, Berglund & Nystedt
// 2021): what the machine feels of the active zone. Every step it is remade as a rigid body that
// inherits the momentary mass, centre of mass, inertia and momentum of the zone's particles, and
// it is solved with the machine in the direct solver through two interfaces (vehicle/
// plane_contact), placed where the zone says:
//   A  bucket–aggregate, on the bucket's cutting plane (the plane through the cutting edge and the
//      top edge), with the bucket–soil friction (0.2);
//   B  terrain–aggregate, on the failure plane from the cutting edge to the surface, with the
//      soil's effective internal friction (phi + psi = 40 deg; paper §4.4: dilatancy "adds directly
//      to the internal friction").
// Each patch is a line contact in the excavation plane: two points on the centre line of its part
// of the plane, at a tenth and nine tenths of its length up from the cutting edge, so it holds the
// torques of that plane as a face does and leaves the aggregate free to roll about the line (a
// patch of four corner points made the vehicle's direct solver cycle between active sets of its
// redundant rows: 'did not converge' within the first second of a G200 cut). Its stiffness is the
// bulk Young's modulus times the aggregate stiffness multiplier (the paper: 4.6 MPa × 0.01) over a
// layer one cell thick: k = E m A / h for a patch of area A.
//
// The interfaces' deformation is a state of their own. The aggregate is remade on the planes every
// step, so a gap measured from its body would always be zero, and a compliant row would then push
// back only with what one step's approach compresses (k u h), a tenth of the soil's resistance at
// G400: the machine would cut through the soil as through mud. Instead each interface keeps the
// depth by which the two sides have pressed into each other, integrated from the relative normal
// velocity the machine's solve gave them (`after_step`), never below zero; the rows see it as the
// gap (-depth), so the interface pushes back with k depth as a spring that builds up while the
// bucket presses and relaxes as it lets go. Without particles in the zone the depths are zero.
//
// Its motion is its own. When the zone first engages, the aggregate starts with the particles'
// momentum; from then on it keeps the velocity and spin the machine's solve gave it, while the
// particles renew its mass, centre and inertia every step (the particles themselves move with the
// bucket as a kinematic body in their own DEM, terrain/multiscale_terrain). Taking the particles'
// momentum every step, as the paper's words "inherits the momentaneous ... momentum" read, put
// back each step the lag of the particles far ahead of the blade (they move slower than it, and
// settle down the face), which the interfaces then had to make up within one step: the type-G
// blade needed 1.13 (G400) and 1.54 (G200) times the FEE for its load; keeping the solved motion,
// 0.95 and 0.96 (docs/multiscale.md). Without particles in the zone the aggregate keeps a nominal
// mass and both interfaces carry no force, so the machine's system keeps its rows and sparsity.
#pragma once
#include <vector>

#include "terrain/multiscale_terrain.hpp"
#include "terrain/penetration.hpp"
#include "vehicle/joints.hpp"
#include "vehicle/multibody.hpp"
#include "vehicle/plane_contact.hpp"
#include "vehicle/point_brake.hpp"

namespace talus {

// a rigid body's share of a set of particles
struct Aggregate {
  int particles = 0;
  double mass = 0.0;                                  // [kg]
  Vec3 centre = Vec3::Zero();                         // centre of mass [m]
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  // world axes, about the centre [kg m^2]
  Vec3 velocity = Vec3::Zero();                       // of the centre [m/s]
  Vec3 omega = Vec3::Zero();  // from the angular momentum about the centre [1/s]
};

// the aggregate of the particles `members` (indices into `particles`), each with its mass from
// `masses` [kg] (the ledger) and its inertia as a solid sphere: mass and centre as sums, inertia by
// the parallel-axis rule, velocity from the momentum, omega solving I omega = L about the centre
Aggregate aggregate_of(const Particles& particles, const std::vector<double>& masses,
                       const std::vector<int>& members);

// the payload's stand-in when the bucket holds nothing [kg], and its radius of gyration [m]: a
// body must have a mass for the direct solve to stay regular; 1 kg is 7e-5 of the machine's
// 15,175 kg (and so its share of an empty machine's motion)
inline constexpr double kIdlePayloadMass = 1.0;
inline constexpr double kIdlePayloadGyration = 0.1;

// the soil the bucket holds outside the zone as a body welded to the bucket (issue 14; the
// default of a type-G dig since 2026-11-29, DiggingOptions::content_inertia): its mass, centre
// and inertia re-set every step from the held particles (`aggregate_of` over them), moving with
// the bucket, so the machine's direct solve feels the load's weight through gravity and its
// inertia through the lock, instead of the weight alone as an external wrench (docs/multiscale.md
// "The bucket's content"). With nothing held it is a nominal kIdlePayloadMass body at the
// bucket's centre of mass. Added to the machine once, so the system's sparsity never changes
class BucketPayload {
 public:
  BucketPayload(vehicle::MultibodySystem& system, int bucket);
  // the held soil for this step (an aggregate of zero particles: nothing held)
  void update(const Aggregate& held);
  int body() const { return body_; }

 private:
  vehicle::MultibodySystem& system_;
  int bucket_;
  int body_;
  vehicle::LockJoint* lock_ = nullptr;
};

// the aggregate's orientation: its principal axes of inertia as the columns of a rotation from
// the world (ascending moments; each axis signed so that its largest world component is positive,
// the third the cross product of the first two, so the same inertia always gives the same frame),
// and the moments about them [kg m^2]. A body with zero inertia (no members) has the identity
struct PrincipalAxes {
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Vec3 moments = Vec3::Zero();
};
PrincipalAxes principal_axes(const Eigen::Matrix3d& inertia);

// the particles of the zone: inside its wedge, whatever the surface (they stand above it)
std::vector<int> zone_members(const Particles& particles, const ActiveZone& zone);

struct AggregateParameters {
  double youngs_modulus = 4.6e6;       // bulk E [Pa], paper §4.4
  double stiffness_multiplier = 0.01;  // paper §4.4
  double damping_steps = 2.0;          // SPOOK damping time of the interfaces, in timesteps
  // [s] the interfaces' SPOOK damping time itself, when positive, instead of damping_steps of the
  // step (a study, DiggingOptions::interface_damping_time: at G200 it, not the step, sets HD27's
  // breakout force, docs/validation.md "HD27's breakout follows the interfaces' damping time")
  double damping_time = 0.0;
  // constraint C, the cutting edge's penetration resistance (terrain/penetration), times this
  // factor: 1 the law as it stands, 0 none (a study of its share, DiggingOptions::edge_resistance;
  // docs/validation.md "Type G against type D": the law is talus's own and moves a dig most)
  double penetration_factor = 1.0;
  PenetrationParameters edge;
  // kg: the mass the aggregate body keeps while the zone holds no particle (its rows carry no
  // force then; a nominal mass keeps the system regular)
  double idle_mass = 1.0;
};

// the interfaces' damping time in use [s]: parameters.damping_time when positive, else
// damping_steps of the step `dt` [s]
double interface_damping_time(const AggregateParameters& parameters, double dt);
// whether a study may ask for this interface damping time [s]: 0 (two steps), or within
// [kMinDampingTime, kMaxDampingTime] (solvers/dem_settings), the particle contacts' study range
bool interface_damping_time_valid(double seconds);

// the aggregate as a body of a machine's multibody system, its two interfaces, and the cutting
// edge's penetration resistance (a vehicle::PointBrake on the bucket's cutting edge along its
// cutting direction, bounded by terrain/penetration's force at the zone's depth)
class AggregateCoupling {
 public:
  // adds the aggregate body and the interfaces A (bucket–aggregate) and B (terrain–aggregate) to
  // `system`, whose body `bucket` is the one the terrain's bucket is
  AggregateCoupling(vehicle::MultibodySystem& system, int bucket, const BulkSoil& soil,
                    const AggregateParameters& parameters = {});

  // before the machine's step: the aggregate remade from the particles in the zone of the
  // terrain's last step, its interfaces placed on the bucket's planes at its state `bucket` (its
  // mesh frame); A reaches as far up the cutting plane as the zone's particles do; `dt` the step
  void update(const MultiscaleTerrain& terrain, const vehicle::BucketMesh& mesh,
              const KinematicBucket& bucket, double dt);

  // after the machine's step: the interfaces' depths from the relative normal velocities it solved
  void after_step(double dt);

  const Aggregate& aggregate() const { return aggregate_; }
  // how far the interfaces are pressed in [m]
  double depth_a() const { return depth_a_; }
  double depth_b() const { return depth_b_; }
  int body() const { return body_; }
  // after the machine's step: the force of interface A on the bucket, of B on the aggregate [N]
  Vec3 force_on_bucket() const { return -a_->force_on_b(); }
  Vec3 terrain_force() const { return b_->force_on_b(); }
  // the penetration resistance's force on the bucket in the last solve [N], against its cutting
  // direction
  double edge_force() const { return brake_->force(); }
  // the same as a force on the bucket in the world [N]
  Vec3 edge_force_on_bucket() const { return -brake_->force() * brake_->direction(); }
  // the most the penetration resistance gives in the next solve [N]: penetration_factor times
  // terrain/penetration's law at the zone's depth (0 while the edge is out of the soil)
  double edge_limit() const { return brake_->max_force(); }
  const vehicle::PlaneContact& interface_a() const { return *a_; }
  const vehicle::PlaneContact& interface_b() const { return *b_; }

  // what the coupling carries from one step to the next, for a saved state: the aggregate of the
  // last update, the interfaces' depths, whether the zone was engaged, and the motion the last
  // solve gave the body (the body itself, its rows' forces and the brake are the machine's
  // system's and saved with it; the interfaces' places are set anew by the next update)
  void save_state(ByteWriter& w) const;
  void restore_state(ByteReader& r);

 private:
  vehicle::MultibodySystem& system_;
  int bucket_;
  int body_;
  BulkSoil soil_;
  AggregateParameters parameters_;
  vehicle::PlaneContact* a_ = nullptr;
  vehicle::PlaneContact* b_ = nullptr;
  vehicle::PointBrake* brake_ = nullptr;
  Aggregate aggregate_;
  double depth_a_ = 0.0, depth_b_ = 0.0;
  bool engaged_now_ = false, engaged_before_ = false;
  Vec3 solved_velocity_ = Vec3::Zero(), solved_omega_ = Vec3::Zero();
};

}  // namespace talus
