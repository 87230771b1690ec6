#include "terrain/aggregate.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "host/error.hpp"
#include "solvers/dem_settings.hpp"

namespace talus {
namespace {

constexpr double kDegree = M_PI / 180.0;

// the points of a patch: on the plane through the cutting edge along `u`, on its centre line, at a
// tenth and nine tenths of its length (see the header)
constexpr int kPatchPoints = 2;
std::vector<Vec3> patch(const ToolEdges& edges, const Vec3& u, double length) {
  const Vec3 mid = 0.5 * (edges.cutting_left + edges.cutting_right);
  return {mid + 0.1 * length * u, mid + 0.9 * length * u};
}

// an interface placed for this step: its patch, normal, the depth it is pressed in (as its gap),
// its stiffness [N/m] and damping time [s]; an interface not engaged carries nothing
void place(vehicle::PlaneContact& contact, bool engaged, std::vector<Vec3> points,
           const Vec3& normal, double depth, double stiffness, double damping_time) {
  vehicle::PlaneContactGeometry g;
  g.active = engaged;
  g.points = std::move(points);
  g.normal = normal;
  g.gaps.assign(g.points.size(), -depth);
  vehicle::PlaneContactParameters p = contact.parameters();
  p.stiffness = stiffness;
  p.damping_time = damping_time;
  contact.set_parameters(p);
  contact.set_geometry(g);
}

}  // namespace

double interface_damping_time(const AggregateParameters& parameters, double dt) {
  return parameters.damping_time > 0.0 ? parameters.damping_time : parameters.damping_steps * dt;
}

bool interface_damping_time_valid(double seconds) {
  return seconds == 0.0 || (seconds >= kMinDampingTime && seconds <= kMaxDampingTime);
}

Aggregate aggregate_of(const Particles& p, const std::vector<double>& masses,
                       const std::vector<int>& members) {
  Aggregate a;
  a.particles = static_cast<int>(members.size());
  if (members.empty()) return a;
  // mass, centre and momentum
  Vec3 moment = Vec3::Zero(), momentum = Vec3::Zero();
  for (int k : members) {
    a.mass += masses[k];
    moment += masses[k] * p.position[k];
    momentum += masses[k] * p.velocity[k];
  }
  a.centre = moment / a.mass;
  a.velocity = momentum / a.mass;
  // inertia and angular momentum about the centre: each sphere's own, and its orbit
  Vec3 spin = Vec3::Zero();
  for (int k : members) {
    const Vec3 d = p.position[k] - a.centre;
    const double own = 0.4 * masses[k] * p.radius[k] * p.radius[k];
    a.inertia += own * Eigen::Matrix3d::Identity() +
                 masses[k] * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
    spin += masses[k] * d.cross(p.velocity[k] - a.velocity) + own * p.omega[k];
  }
  a.omega = a.inertia.ldlt().solve(spin);
  return a;
}

BucketPayload::BucketPayload(vehicle::MultibodySystem& system, int bucket)
    : system_(system), bucket_(bucket) {
  vehicle::RigidBody body;
  body.name = "bucket payload";
  body.mass = kIdlePayloadMass;
  body.inertia = Eigen::Matrix3d::Identity() *
                 (kIdlePayloadMass * kIdlePayloadGyration * kIdlePayloadGyration);
  body.position = system.body(bucket).position;
  body.velocity = system.body(bucket).velocity;
  body.angular_velocity = system.body(bucket).angular_velocity;
  body_ = system.add_body(body);
  lock_ = &system.add_constraint(
      std::make_unique<vehicle::LockJoint>(system.bodies(), bucket, body_, body.position));
  lock_->name = "bucket payload lock";
}

void BucketPayload::update(const Aggregate& held) {
  const vehicle::RigidBody bucket = system_.body(bucket_);
  vehicle::RigidBody& body = system_.body(body_);
  // the held soil's mass and inertia (world axes, the body unrotated), or the idle stand-in at
  // the bucket's centre
  body.orientation = Eigen::Quaterniond::Identity();
  if (held.particles > 0) {
    body.mass = held.mass;
    body.inertia = held.inertia;
    body.position = held.centre;
  } else {
    body.mass = kIdlePayloadMass;
    body.inertia = Eigen::Matrix3d::Identity() *
                   (kIdlePayloadMass * kIdlePayloadGyration * kIdlePayloadGyration);
    body.position = bucket.position;
  }
  // moving with the bucket, and locked to it where both now stand
  body.velocity = bucket.point_velocity(body.position);
  body.angular_velocity = bucket.angular_velocity;
  lock_->reanchor(system_.bodies(), body.position);
}

PrincipalAxes principal_axes(const Eigen::Matrix3d& inertia) {
  PrincipalAxes out;
  if (inertia.isZero(0.0)) return out;
  // the symmetric eigenproblem: Eigen sorts the moments ascending
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(inertia);
  Eigen::Matrix3d axes = solver.eigenvectors();
  // each axis's sign fixed by its largest world component, the third made right-handed
  for (int c = 0; c < 2; ++c) {
    Eigen::Index largest = 0;
    axes.col(c).cwiseAbs().maxCoeff(&largest);
    if (axes(largest, c) < 0.0) axes.col(c) = -axes.col(c);
  }
  axes.col(2) = axes.col(0).cross(axes.col(1));
  out.orientation = Eigen::Quaterniond(axes).normalized();
  out.moments = solver.eigenvalues();
  return out;
}

std::vector<int> zone_members(const Particles& particles, const ActiveZone& zone) {
  std::vector<int> members;
  if (zone.depth <= 0.0) return members;
  for (size_t k = 0; k < particles.size(); ++k)
    if (zone.contains(particles.position[k])) members.push_back(static_cast<int>(k));
  return members;
}

AggregateCoupling::AggregateCoupling(vehicle::MultibodySystem& system, int bucket,
                                     const BulkSoil& soil, const AggregateParameters& parameters)
    : system_(system), bucket_(bucket), soil_(soil), parameters_(parameters) {
  vehicle::RigidBody body;
  body.name = "aggregate";
  body.mass = parameters.idle_mass;
  body.position = system.body(bucket).position;
  body_ = system.add_body(body);
  vehicle::PlaneContactParameters a;
  a.friction = soil.tool_friction;
  vehicle::PlaneContactParameters b;
  b.friction = std::tan(soil.effective_friction_deg() * kDegree);
  a_ = &system.add_constraint(
      std::make_unique<vehicle::PlaneContact>(bucket, body_, kPatchPoints, a));
  a_->name = "aggregate interface A (bucket)";
  b_ = &system.add_constraint(
      std::make_unique<vehicle::PlaneContact>(vehicle::kWorld, body_, kPatchPoints, b));
  b_->name = "aggregate interface B (terrain)";
  brake_ = &system.add_constraint(std::make_unique<vehicle::PointBrake>(bucket));
  brake_->name = "penetration resistance (cutting edge)";
}

void AggregateCoupling::update(const MultiscaleTerrain& terrain, const vehicle::BucketMesh& mesh,
                               const KinematicBucket& bucket, double dt) {
  // the zone of the terrain's last step (predicted before it excavated: the voxels now stand on
  // its failure plane), and the particles in it
  const ToolEdges edges = bucket_edges(mesh, bucket);
  const ActiveZone& zone = terrain.last_step().zone;
  const Particles& particles = terrain.particles();
  const std::vector<int> members = zone_members(particles, zone);
  aggregate_ = aggregate_of(particles, terrain.particle_masses(), members);
  // engaged while the cutting edge is under the soil with particles in the zone, whatever its
  // speed: a bucket that slows against the pile meets the soil all the more (the speed threshold
  // decides only what turns dynamic)
  const bool engaged = zone.depth > 0.0 && aggregate_.particles > 0;
  if (!engaged) depth_a_ = depth_b_ = 0.0;
  engaged_before_ = engaged_now_;
  engaged_now_ = engaged;

  // the body: the particles' mass, inertia and momentum, or a nominal body at the cutting edge
  vehicle::RigidBody& body = system_.body(body_);
  body.orientation = Eigen::Quaterniond::Identity();
  if (aggregate_.particles > 0) {
    body.mass = aggregate_.mass;
    // at least the inertia of a solid block of its mass as wide as the zone and a cell deep: the
    // aggregate stands for the wedge, and a zone of one or two particles would otherwise be a
    // body with almost no inertia, on which the interfaces' four normal rows left the vehicle's
    // direct solver cycling (a force-feedback cycle at G400)
    const double h_cell = terrain.voxels().cell();
    const double block = aggregate_.mass * (zone.width * zone.width + h_cell * h_cell) / 12.0;
    body.inertia = aggregate_.inertia;
    for (int k = 0; k < 3; ++k) body.inertia(k, k) = std::max(body.inertia(k, k), block);
    body.position = aggregate_.centre;
    if (engaged_before_) {
      // engaged since the last step: the motion the machine's solve gave it (see the header)
      body.velocity = solved_velocity_;
      body.angular_velocity = solved_omega_;
    } else {
      body.velocity = aggregate_.velocity;
      body.angular_velocity = aggregate_.omega;
    }
  } else {
    const double h = terrain.voxels().cell();
    body.mass = parameters_.idle_mass;
    body.inertia = Eigen::Matrix3d::Identity() * (parameters_.idle_mass * h * h);
    body.position = zone.tip;
    body.velocity = bucket.velocity;
    body.angular_velocity = Vec3::Zero();
  }

  // the interfaces' damping time: the study's, or damping_steps of the step
  const double damping_time = interface_damping_time(parameters_, dt);

  // interface A on the cutting plane, as far up as the soil reaches (or the top edge)
  const double h = terrain.voxels().cell();
  const double e_m = parameters_.youngs_modulus * parameters_.stiffness_multiplier;
  const Vec3 top = 0.5 * (edges.top_left + edges.top_right) - zone.tip;
  const Vec3 u_tool = top.normalized();
  Vec3 n_a = zone.along.cross(u_tool).normalized();
  if (n_a.dot(zone.forward) < 0.0) n_a = -n_a;
  // as far up the cutting plane as the zone's particles reach
  double reach = 0.0;
  for (int k : members)
    reach = std::max(reach, (particles.position[k] - zone.tip).dot(u_tool) + particles.radius[k]);
  const double length_a = std::clamp(reach, h, top.norm());
  place(*a_, engaged, patch(edges, u_tool, length_a), n_a, depth_a_,
        e_m * zone.width * length_a / h, damping_time);

  // interface B on the failure plane, from the cutting edge to where it leaves the surface
  const double beta = zone.failure_angle_deg * kDegree;
  const Vec3 u_fail = std::cos(beta) * zone.forward + std::sin(beta) * Vec3::UnitZ();
  const Vec3 n_b = -std::sin(beta) * zone.forward + std::cos(beta) * Vec3::UnitZ();
  const double length_b = std::max(zone.reach_ahead / std::max(std::cos(beta), 1e-3), h);
  place(*b_, engaged, patch(edges, u_fail, length_b), n_b, depth_b_,
        e_m * zone.width * length_b / h, damping_time);

  // constraint C: the cutting edge along the bucket's cutting direction (its profile frame's x),
  // resisted while it is under the soil's surface
  const vehicle::RigidBody& bucket_body = system_.body(bucket_);
  const double resistance = parameters_.penetration_factor *
                            penetration_resistance(zone.depth, zone.width, soil_, parameters_.edge);
  brake_->set(bucket_body.point_to_local(bucket.position), bucket.orientation * Vec3::UnitX(),
              resistance);
}

void AggregateCoupling::after_step(double dt) {
  const vehicle::RigidBody& aggregate = system_.body(body_);
  solved_velocity_ = aggregate.velocity;
  solved_omega_ = aggregate.angular_velocity;
  const vehicle::RigidBody& bucket = system_.body(bucket_);
  // the relative normal velocity at each patch's centre (positive: the sides part)
  const auto centre = [](const std::vector<Vec3>& points) {
    Vec3 c = Vec3::Zero();
    for (const Vec3& p : points) c += p;
    return Vec3(c / static_cast<double>(points.size()));
  };
  const vehicle::PlaneContactGeometry& ga = a_->geometry();
  const vehicle::PlaneContactGeometry& gb = b_->geometry();
  if (ga.active) {
    const Vec3 c = centre(ga.points);
    const double parting = (aggregate.point_velocity(c) - bucket.point_velocity(c)).dot(ga.normal);
    depth_a_ = std::max(0.0, depth_a_ - dt * parting);
  }
  if (gb.active) {
    const double parting = aggregate.point_velocity(centre(gb.points)).dot(gb.normal);
    depth_b_ = std::max(0.0, depth_b_ - dt * parting);
  }
}

void AggregateCoupling::save_state(ByteWriter& w) const {
  w.i64(aggregate_.particles);
  w.f64(aggregate_.mass);
  write_matrix(w, aggregate_.centre);
  write_matrix(w, aggregate_.inertia);
  write_matrix(w, aggregate_.velocity);
  write_matrix(w, aggregate_.omega);
  w.f64(depth_a_);
  w.f64(depth_b_);
  w.u8(engaged_now_ ? 1 : 0);
  w.u8(engaged_before_ ? 1 : 0);
  write_matrix(w, solved_velocity_);
  write_matrix(w, solved_omega_);
}

void AggregateCoupling::restore_state(ByteReader& r) {
  Aggregate a;
  const std::int64_t particles = r.i64("aggregate");
  if (particles < 0 || particles > std::numeric_limits<int>::max())
    throw InputError(r.where() + ": an aggregate of " + std::to_string(particles) +
                     " particles (corrupt)");
  a.particles = static_cast<int>(particles);
  a.mass = r.f64("aggregate");
  read_matrix(r, a.centre, "aggregate");
  read_matrix(r, a.inertia, "aggregate");
  read_matrix(r, a.velocity, "aggregate");
  read_matrix(r, a.omega, "aggregate");
  const double depth_a = r.f64("aggregate interfaces"), depth_b = r.f64("aggregate interfaces");
  if (!(a.mass >= 0.0) || !(depth_a >= 0.0) || !(depth_b >= 0.0))
    throw InputError(r.where() + ": an aggregate of " + std::to_string(a.particles) +
                     " particles, " + std::to_string(a.mass) + " kg, pressed in by " +
                     std::to_string(depth_a) + " and " + std::to_string(depth_b) + " m (corrupt)");
  const bool now = r.u8("aggregate") != 0, before = r.u8("aggregate") != 0;
  Vec3 velocity, omega;
  read_matrix(r, velocity, "aggregate");
  read_matrix(r, omega, "aggregate");
  aggregate_ = a;
  depth_a_ = depth_a;
  depth_b_ = depth_b;
  engaged_now_ = now;
  engaged_before_ = before;
  solved_velocity_ = velocity;
  solved_omega_ = omega;
}

}  // namespace talus
