#include "solvers/split_solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "host/error.hpp"
#include "host/stage_times.hpp"
#include "solvers/tolerance_schedule.hpp"

namespace talus {

SplitSolver::SplitSolver(Device& dev, DemWorld& dem, vehicle::WheelLoader& loader,
                         const CouplingSettings& settings, const embree::Device& embree)
    : dev_(dev), dem_(dem), loader_(loader), settings_(settings), scene_(loader.bucket_mesh(), embree),
      selection_(dev), block_(dev) {
  if (settings.max_passes < 1) throw InputError("CouplingSettings.max_passes: must be at least 1");
  if (!(settings.tolerance > 0.0)) throw InputError("CouplingSettings.tolerance: must be positive [m/s]");
  if (!(settings.material.friction >= 0.0) || !(settings.material.rolling >= 0.0))
    throw InputError("CouplingSettings.material: friction and rolling must not be negative");
  for (const Vec3& v : scene_.vertices()) bucket_reach_ = std::max(bucket_reach_, v.norm());
}

double SplitSolver::point_speed_difference(const Vec6& a, const Vec6& b, const Vec3& com) const {
  // |dv + dw x (x - com)| <= |dv| + |dw| |x - com|, with |x - com| bounded by the reach from the
  // mesh origin (the tip) plus the distance of the centre of mass from it
  const double reach = bucket_reach_ + (loader_.bucket_tip_world() - com).norm();
  return (a.head<3>() - b.head<3>()).norm() + (a.tail<3>() - b.tail<3>()).norm() * reach;
}

BucketFaceForces bucket_face_forces(const std::vector<ContactRow>& rows,
                                    const Eigen::Quaterniond& orientation, double h) {
  // a contact's face from its normal in the bucket's frame: cos 45 deg from +-z, then from +-x
  // (a unit normal cannot be within 45 deg of both)
  const double cos45 = std::sqrt(0.5);
  const Vec3 x = orientation * Vec3::UnitX(), z = orientation * Vec3::UnitZ();
  BucketFaceForces f;
  for (const ContactRow& r : rows) {
    const Vec3 force = (r.impulse_n * r.normal + r.impulse_t) / h;
    const double nz = r.normal.dot(z);
    if (nz >= cos45)
      f.below += force;
    else if (nz <= -cos45)
      f.inside += force;
    else if (std::abs(r.normal.dot(x)) > cos45)
      f.across += force;
  }
  return f;
}

void SplitSolver::step() {
  stats_ = CouplingStats{};
  const double h = dem_.settings().dt;
  vehicle::MultibodySystem& vehicle = loader_.system();
  const vehicle::RigidBody& bucket_body = vehicle.body(loader_.bucket_body());
  const Vec3 com = bucket_body.position;
  const Vec6 twist_before = bucket_body.twist();

  // 1. rows of both sides from the start-of-step state
  {
    StageScope stage(dev_, "direct_solve");
    vehicle.assemble(h);
  }
  dem_.begin_step();
  const StepParams params = from_device(dem_.params());

  // 2. particles near the bucket and their contacts with it
  const NearBucket n = find_near_bucket(h, com, twist_before);

  // 3. the bucket rows, warm started, with the mobility of a first vehicle solve
  Vec6 warm_impulse = Vec6::Zero();
  std::vector<ContactRow> rows = start_bucket_rows(n, params, com, twist_before, &warm_impulse);

  // 4-5. velocities: the sweeps and the outer passes
  const Vec6 impulse = solve_coupled(rows, warm_impulse, com);
  stats_.impulse = impulse;
  stats_.wrench = impulse / h;
  stats_.faces = bucket_face_forces(rows, bucket_body.orientation, h);

  // 6. both sides move; the bucket impulses are kept for the next warm start
  if (settings_.record_residual) {
    StageScope stage(dev_, "residual");
    stats_.particle_residual = dem_.residual();
  }
  {
    StageScope stage(dev_, "bucket_row_setup");
    previous_ = talus::bucket_impulses(rows, n.candidates);
    std::stable_sort(
        previous_.begin(), previous_.end(),
        [](const BucketImpulse& a, const BucketImpulse& b) { return a.particle < b.particle; });
  }
  dem_.end_step();
  StageScope stage(dev_, "integration");
  vehicle.integrate();
}

SplitSolver::NearBucket SplitSolver::find_near_bucket(double h, const Vec3& com,
                                                      const Vec6& twist_before) {
  // the contact range covers what the bucket and a particle can close within the step
  // (speculative)
  NearBucket n;
  const BucketPose pose = bucket_pose(loader_);
  const double r_max = dem_.max_radius();
  const double bucket_speed = twist_before.head<3>().norm() + twist_before.tail<3>().norm() * (bucket_reach_ +
                              (pose.position - com).norm());
  const double reach = 2.0 * h * (bucket_speed + dem_.settings().max_speed);
  if (dem_.size() > 0) {
    // device box selection, the candidates' state
    const double margin_box = dem_.settings().margin_rel + reach / std::max(r_max, 1e-12);
    const Aabb box = candidate_box(scene_.world_bounds(pose), r_max, margin_box);
    DemBuffers& b = dem_.buffers();
    {
      StageScope stage(dev_, "bucket_selection");
      n.candidates = selection_.select(b.position, dem_.size(), box);
      n.near = block_.gather(n.candidates, b.position, b.velocity, b.omega);
    }
    StageScope stage(dev_, "embree");
    std::vector<int> local(n.candidates.size());
    for (size_t k = 0; k < local.size(); ++k) local[k] = static_cast<int>(k);
    // Embree contacts, each particle's own margin: the relative one plus the speculative reach
    // in its radii
    const auto t0 = std::chrono::steady_clock::now();
    double r_min = r_max;
    for (double r : n.near.radius) r_min = std::min(r_min, r);
    const double margin = dem_.settings().margin_rel + reach / std::max(r_min, 1e-12);
    n.contacts = scene_.find_bucket_contacts(n.near, local, pose, margin);
    stats_.embree_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  stats_.candidates = static_cast<int>(n.candidates.size());
  stats_.bucket_contacts = static_cast<int>(n.contacts.size());
  for (const BucketContact& c : n.contacts)
    stats_.max_overlap_rel = std::max(stats_.max_overlap_rel, -c.gap / n.near.radius[c.particle]);
  return n;
}

std::vector<ContactRow> SplitSolver::start_bucket_rows(const NearBucket& n,
                                                       const StepParams& params, const Vec3& com,
                                                       const Vec6& twist_before,
                                                       Vec6* warm_impulse) {
  // match last step's impulses (by particle of the whole system)
  StageScope stage(dev_, "bucket_row_setup");
  const double h = dem_.settings().dt;
  vehicle::MultibodySystem& vehicle = loader_.system();
  std::vector<BucketContact> keyed = n.contacts;
  for (auto& c : keyed) c.particle = n.candidates[c.particle];
  const std::vector<int> match = dem_.settings().warm_start ? match_bucket_contacts(keyed, previous_)
                                                            : std::vector<int>();
  BucketBody start;
  start.velocity = twist_before.head<3>();
  start.omega = twist_before.tail<3>();
  // the rows' impulses do not depend on the mobility: make them, take their wrench, solve, and
  // give them the effective masses of the mobility that solve yields
  std::vector<ContactRow> rows = make_bucket_rows(n.contacts, n.near, start, com, params,
                                                  settings_.material, previous_, match);
  *warm_impulse = bucket_wrench_impulse(rows);
  loader_.set_bucket_wrench(*warm_impulse / h);
  {
    StageScope solve(dev_, "direct_solve");
    vehicle.solve();
  }
  start.mobility = loader_.bucket_mobility();
  // the coloured sweep's colours, by particle; its rows see the bucket split among a colour's
  BucketColouring colouring;
  if (settings_.bucket_sweep == BucketSweep::Coloured) {
    std::vector<int> particle_of_row;
    particle_of_row.reserve(rows.size());
    for (const ContactRow& r : rows) particle_of_row.push_back(r.a);
    colouring = colour_bucket_rows(particle_of_row);
  }
  set_bucket_effective_masses(rows, n.contacts, n.near, start.mobility, colouring.split);
  // the rows (particle indices of the whole system) and the solved bucket to the device
  std::vector<TlRow> device_rows;
  device_rows.reserve(rows.size());
  for (auto& r : rows) {
    TlRow d = to_device(r);
    d.a = n.candidates[r.a];
    device_rows.push_back(d);
  }
  StageScope upload(dev_, "transfers");
  block_.set_rows(device_rows, colouring);
  BucketBody solved;
  const Vec6 twist0 = vehicle.solved_twist(loader_.bucket_body());
  solved.velocity = twist0.head<3>();
  solved.omega = twist0.tail<3>();
  solved.mobility = start.mobility;
  block_.set_bucket(solved);
  return rows;
}

Vec6 SplitSolver::solve_coupled(std::vector<ContactRow>& rows, const Vec6& warm_impulse,
                                const Vec3& com) {
  // gravity and warm start of both kinds of rows
  const double h = dem_.settings().dt;
  vehicle::MultibodySystem& vehicle = loader_.system();
  {
    StageScope stage(dev_, "warm_start");
    dem_.apply_gravity();
    dem_.warm_start();
    if (dem_.settings().warm_start)
      block_.warm_start(dem_.buffers().velocity, dem_.buffers().omega);
  }
  const int iterations = dem_.settings().iterations;
  const int pass_sweeps = std::max(1, static_cast<int>(std::lround(settings_.pass_sweep_fraction * iterations)));
  Vec6 impulse = warm_impulse;
  for (int pass = 0; pass < settings_.max_passes; ++pass) {
    // the pass's sweeps, particle rows and bucket rows in turn; with a tolerance
    // (DemSettings::tolerance) the particle rows' residual, looked at where the schedule puts
    // the looks (solvers/tolerance_schedule), ends them early
    const int sweeps = pass == 0 ? iterations : pass_sweeps;
    const double tolerance = dem_.settings().tolerance;
    std::optional<ToleranceSchedule> schedule;
    if (tolerance > 0.0) schedule.emplace(tolerance);
    for (int it = 0; it < sweeps; ++it) {
      {
        StageScope stage(dev_, "particle_sweeps");
        dem_.sweep_fixed(1);
      }
      {
        StageScope stage(dev_, "bucket_rows");
        block_.sweep(dem_.buffers().velocity, dem_.buffers().omega);
      }
      ++stats_.sweeps;
      if (schedule && it + 1 == schedule->next_look() && it + 1 < sweeps) {
        StageScope stage(dev_, "tolerance_check");
        if (schedule->look(it + 1, dem_.residual())) break;
      }
    }
    ++stats_.passes;
    if (rows.empty()) break;  // nothing touches the bucket (and the vehicle solved without load)
    // the rows' impulses back to double, their wrench into the direct solve
    StageScope stage(dev_, "transfers");
    const std::vector<TlRow> solved_rows = block_.rows();
    for (size_t k = 0; k < rows.size(); ++k) {
      const ContactRow r = from_device(solved_rows[k]);
      rows[k].impulse_n = r.impulse_n;
      rows[k].impulse_t = r.impulse_t;
      rows[k].impulse_r = r.impulse_r;
    }
    impulse = bucket_wrench_impulse(rows);
    const Vec6 twist_sweeps = block_.bucket().twist();
    loader_.set_bucket_wrench(impulse / h);
    {
      StageScope solve(dev_, "direct_solve");
      vehicle.solve();
    }
    const Vec6 twist_direct = vehicle.solved_twist(loader_.bucket_body());
    stats_.residual = point_speed_difference(twist_direct, twist_sweeps, com);
    if (stats_.residual < settings_.tolerance || pass + 1 == settings_.max_passes) break;
    // the vehicle answered differently: go on from its twist and its new mobility
    BucketBody next;
    next.velocity = twist_direct.head<3>();
    next.omega = twist_direct.tail<3>();
    next.mobility = loader_.bucket_mobility();
    block_.set_bucket(next);
  }
  return impulse;
}

void SplitSolver::save_state(ByteWriter& w) const { write_bucket_impulses(w, previous_); }

void SplitSolver::restore_state(ByteReader& r) { previous_ = read_bucket_impulses(r, dem_.size()); }

}  // namespace talus
