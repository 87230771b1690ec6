#include "terrain/multiscale_terrain.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <locale>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <unordered_map>

#include "host/error.hpp"
#include "host/stage_times.hpp"
#include "solvers/tool_world.hpp"
#include "terrain/bucket_fill.hpp"

namespace talus {
namespace {

// how high above an excavated column's floor spawning looks for room [m]: the soil a bucket
// pushes heaps up in front of it, to about the default pile's height (SPEC §2.5: 2 m)
constexpr double kSpawnHeight = 2.0;
// the spread of the particles' diameters, as the type-D piles' (terrain/pile: D ± 10 %)
constexpr double kSizeSpread = 0.1;

// a hash of particle centres by cell, for "does a new particle touch one already there?"
class CentreGrid {
 public:
  explicit CentreGrid(double cell) : cell_(cell) {}
  void add(const Vec3& x, double r) {
    grid_[key(x)].push_back(static_cast<int>(centres_.size()));
    centres_.push_back(x);
    radii_.push_back(r);
  }
  bool touches(const Vec3& x, double r) const {
    const long cx = std::lround(std::floor(x.x() / cell_)),
               cy = std::lround(std::floor(x.y() / cell_)),
               cz = std::lround(std::floor(x.z() / cell_));
    for (long dz = -1; dz <= 1; ++dz)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dx = -1; dx <= 1; ++dx) {
          const auto it = grid_.find(pack(cx + dx, cy + dy, cz + dz));
          if (it == grid_.end()) continue;
          for (int k : it->second)
            if ((centres_[k] - x).norm() < radii_[k] + r) return true;
        }
    return false;
  }

 private:
  static long long pack(long x, long y, long z) {
    return ((static_cast<long long>(x) & 0x1fffff) << 42) |
           ((static_cast<long long>(y) & 0x1fffff) << 21) | (static_cast<long long>(z) & 0x1fffff);
  }
  long long key(const Vec3& x) const {
    return pack(std::lround(std::floor(x.x() / cell_)), std::lround(std::floor(x.y() / cell_)),
                std::lround(std::floor(x.z() / cell_)));
  }
  double cell_;
  std::unordered_map<long long, std::vector<int>> grid_;
  std::vector<Vec3> centres_;
  std::vector<double> radii_;
};

// the mass of a sphere of diameter d at density rho [kg], as spawning has always counted it
double sphere_mass(double d, double rho) { return rho * M_PI / 6.0 * d * d * d; }
// the diameter of a sphere of mass m at density rho [m], sphere_mass's inverse
double sphere_diameter(double m, double rho) { return std::cbrt(6.0 * m / (M_PI * rho)); }

BucketPose pose_of(const KinematicBucket& b) {
  BucketPose pose;
  pose.position = b.position;
  pose.orientation = b.orientation;
  return pose;
}

}  // namespace

ToolEdges bucket_edges(const vehicle::BucketMesh& mesh, const KinematicBucket& bucket) {
  const BucketPose pose = pose_of(bucket);
  const double half = 0.5 * mesh.inner_width;
  const Vec3 lip = mesh.profile.empty() ? Vec3(0, 0, 1) : mesh.profile.back();
  ToolEdges edges;
  edges.cutting_left = pose.to_world(Vec3(0.0, half, 0.0));
  edges.cutting_right = pose.to_world(Vec3(0.0, -half, 0.0));
  edges.top_left = pose.to_world(Vec3(lip.x(), half, lip.z()));
  edges.top_right = pose.to_world(Vec3(lip.x(), -half, lip.z()));
  // the frame's origin is the cutting edge's middle: its velocity is the frame's
  edges.velocity = bucket.velocity;
  return edges;
}

MultiscaleTerrain::MultiscaleTerrain(Device& dev, const PileProfile& profile,
                                     const FidelityPreset& level, const vehicle::BucketMesh& bucket,
                                     const KinematicBucket& start, const MultiscaleOptions& options,
                                     const embree::Device& embree)
    : level_(level),
      options_(options),
      profile_(profile),
      voxels_(VoxelTerrain::from_profile(profile,
                                         [&] {
                                           VoxelTerrainOptions v;
                                           v.cell = level.diameter;
                                           v.front_margin = options.front_margin;
                                           // room above the pile for the heap a bucket pushes up
                                           // and the soil merged onto it
                                           v.head_room = kSpawnHeight + 2.0 * level.diameter;
                                           return v;
                                         }())),
      bucket_mesh_(bucket),
      bucket_scene_(bucket, embree),
      sizes_(options.seed) {
  if (!find_multiscale_preset(level.name))
    throw InputError("multiscale terrain: level '" + level.name +
                     "' is not a type-G level (G50, G100, G200, G400)");
  if (!(options.seed_diameter >= kMinSeedDiameter && options.seed_diameter <= 1.0))
    throw InputError("multiscale terrain: seed_diameter " + std::to_string(options.seed_diameter) +
                     " is not in [0.1, 1]: a seed is that fraction of its full diameter (1: full "
                     "size)");
  if (!(options.growth_speed > 0.0 && std::isfinite(options.growth_speed)))
    throw InputError("multiscale terrain: growth_speed " + std::to_string(options.growth_speed) +
                     " m/s is not a positive speed");
  if (!(options.pressed_depth >= 0.0 && options.pressed_depth < level.diameter))
    throw InputError("multiscale terrain: pressed_depth " + std::to_string(options.pressed_depth) +
                     " m is not a depth in [0, a cell): how far the bucket may press into the "
                     "voxels before push_aside moves the soil (0, or kPressedDepth with the "
                     "terrain's support)");
  if (!(options.excavation_reach >= 0.0 && std::isfinite(options.excavation_reach)))
    throw InputError("multiscale terrain: excavation_reach " +
                     std::to_string(options.excavation_reach) +
                     " m is not a distance ahead of the cutting edge (0: the whole zone)");
  if (!(options.merge_speed > 0.0 && std::isfinite(options.merge_speed)))
    throw InputError("multiscale terrain: merge_speed " + message_number(options.merge_speed) +
                     " m/s is not a positive speed: a particle slower than it may merge back "
                     "into the voxels (" +
                     message_number(kMergeSpeed) + ", the default)");
  check_avalanche_options(options.avalanche);
  DemSettings settings;
  settings.dt = level.dt;
  settings.iterations = level.iterations;
  settings.max_speed = options.max_particle_speed;
  settings.one_group_rows = options.one_group_rows;
  settings.serial_lanes = options.serial_lanes;
  settings.sweep_parts = options.sweep_parts;
  settings.pair_reach = options.pair_reach;
  settings.relaxation = options.relaxation;
  dem_ = std::make_unique<DemWorld>(dev, options.particle_material, settings,
                                    pile_bounds(profile, level.diameter), pile_container(profile));
  Tool tool;
  tool.mesh = bucket;
  tool.position = start.position;
  tool.orientation = start.orientation;
  tool.velocity = start.velocity;
  tool.omega = start.omega;
  tool.material = options.bucket_material;
  tools_ = std::make_unique<ToolWorld>(dev, *dem_, std::vector<Tool>{tool}, embree);
  // the zone where the bucket starts, so that what reads the last step's zone before the first
  // step (the aggregate) sees the real cutting edge and not an empty default: a zone of zero
  // width gave the aggregate's interfaces zero stiffness, and the machine's first step lurched
  // back at up to 1 m/s (docs/multiscale.md)
  last_.zone = zone_for(start, state_);
}

ActiveZone MultiscaleTerrain::zone_for(const KinematicBucket& bucket,
                                       const Particles& particles) const {
  // the bucket's own load is not soil over its edge: counted, it read the heap in a full bucket
  // standing at the rear wall as 1.6-1.8 m of soil over an edge that stood above the terrain, and
  // the penetration resistance and the interfaces held the curled bucket down while the lift
  // raised the machine's rear (docs/multiscale.md, "The bucket's load is not soil over its edge")
  std::vector<char> held(particles.size(), 0);
  for (int k : particles_in_bucket(particles, bucket_mesh_, pose_of(bucket))) held[k] = 1;
  const std::vector<double> surface = soil_surface(particles, held);
  return predict_active_zone(voxels_, bucket_edges(bucket_mesh_, bucket), options_.soil, &surface);
}

void MultiscaleTerrain::download_particles() {
  state_ = ledger_.empty() ? Particles{} : dem_->particles();
  // the DEM leaves fixed particles where the step began: the riding ones (rest_in_bucket) are
  // where the bucket took them by the step's end, with their own masses, as every reader (the
  // loaded mass, the held load's body, the zone, the output) expects the step's particles; the
  // next step places them from the bucket's pose again and fixes them on the device
  for (size_t k = 0; k < rest_.size() && k < state_.size(); ++k) {
    if (!rest_[k].resting) continue;
    state_.position[k] += level_.dt * state_.velocity[k];
    state_.inv_mass[k] = rest_[k].inv_mass;
    state_.inv_inertia[k] = rest_[k].inv_inertia;
  }
}

MultiscaleTerrain::~MultiscaleTerrain() = default;

MassBalance MultiscaleTerrain::mass_balance() const {
  MassBalance m;
  m.solid = voxels_.total_mass();
  m.pool = pool_;
  for (double x : ledger_) m.particles += x;
  return m;
}

void MultiscaleTerrain::step(const KinematicBucket& bucket) {
  last_ = MultiscaleStep{};
  const BucketPose pose = pose_of(bucket);
  // each part is a stage of a profiled run (talus bench dig at a G level)
  Device& dev = dem_->device();
  // 1. the zone on the soil's surface (the voxels, raised to the tops of the particles heaped on
  // them), and its solid soil into the pool
  Particles particles = state_;
  std::optional<StageScope> stage(std::in_place, dev, "zone_excavation");
  last_.zone = zone_for(bucket, particles);
  std::vector<ExcavatedColumn> columns;
  const DynamicSoil dynamic = excavate(voxels_, within_reach(last_.zone, options_.excavation_reach),
                                       options_.soil, &columns);
  pool_ += dynamic.mass;
  last_.excavated = dynamic.mass;
  // the soil the rest of the bucket overlaps (its heel, its body outside the zone) pushed aside
  // onto the nearest open columns; what finds no room turns dynamic
  std::vector<Vec3> bucket_vertices;
  bucket_vertices.reserve(bucket_scene_.vertices().size());
  for (const Vec3& v : bucket_scene_.vertices()) bucket_vertices.push_back(pose.to_world(v));
  const std::vector<double> underside =
      tool_underside(voxels_, bucket_vertices, bucket_scene_.triangles());
  const PushedSoil pushed = push_aside(voxels_, underside, options_.soil, options_.pressed_depth);
  pool_ += pushed.left.mass;
  last_.excavated += pushed.left.mass;

  // 2. particles from the pool; 4. resting particles back (on the state the last step left)
  stage.emplace(dev, "spawn_merge");
  std::vector<int> new_index_of_old;
  last_.merged = merge(particles, bucket, &new_index_of_old);
  last_.grown = grow(particles);
  last_.spawned = spawn(particles, columns, pose);
  // the bucket's resting load rides with it (a study; off, nothing changes)
  const bool rode = options_.rest_in_bucket && ride_with_bucket(particles, bucket);
  if (last_.merged > 0 || last_.spawned > 0) {
    // the pairs of the particles that stay, and their contacts with the bucket, keep their warm
    // start (and colours) (until 2026-11-27 every contact started from zero at a step that merged
    // or spawned any particle); the grown ones' sizes go with them
    dem_->renumber_particles(particles, new_index_of_old);
    tools_->renumber_particles(new_index_of_old);
  } else if (last_.grown > 0 || rode) {
    // the same particles, some larger or riding with the bucket: their contacts, impulses and
    // colours stay
    dem_->resize_particles(particles);
  }

  // 3. one DEM step with the bucket kinematic, on the voxel surface near the particles
  Tool& tool = tools_->tool(0);
  tool.position = bucket.position;
  tool.orientation = bucket.orientation;
  tool.velocity = bucket.velocity;
  tool.omega = bucket.omega;
  if (!ledger_.empty()) {
    stage.emplace(dev, "terrain_geometry");
    // the broad phase's grid over the particles' cells alone, not the container's (the same
    // contacts in the same order: DemWorld::set_grid_region), then the boxes binned on it
    dem_->set_grid_region(centres_box(particles));
    const std::vector<StaticGeom> geoms = geometry(particles);
    // boxes remade for this step's columns: the particle pairs keep their warm start (until
    // 2026-11-27 every contact started from zero here, each step)
    dem_->set_geoms(geoms, GeomChange::Renumbered);
    // the DEM's own stages (contacts, colouring, sweeps) are charged to themselves
    stage.emplace(dev, "zone_particles");
    tools_->step();
    last_.bucket_wrench = tools_->load(0).wrench;
  }
  // the particles as the step left them, downloaded once for everyone who reads them
  stage.emplace(dev, "transfers");
  download_particles();

  // 5. the surface relaxes, but not into the columns the bucket stands on: the slopes into the
  // pit under the bucket would refill it every step, and the bucket would move the same soil
  // again (measured with the soil turned dynamic instead of pushed: 30 kg a step at G200, s =
  // 0.755, the bucket standing still against the rear wall)
  stage.emplace(dev, "avalanche");
  const std::vector<char> closed = closed_columns(voxels_, underside);
  last_.avalanched = avalanche(voxels_, level_.dt, options_.avalanche, &closed).moved_mass;
  time_ += level_.dt;
}

bool MultiscaleTerrain::ride_with_bucket(Particles& particles, const KinematicBucket& bucket) {
  const BucketPose pose = pose_of(bucket);
  const double h = level_.dt;
  const double rho = options_.particle_material.density;
  const Vec3 g = dem_->settings().gravity;
  // the bucket's angular and linear acceleration over the last step (zero at the first), so that
  // a particle's gravity in the bucket's frame is the gravity less its point's acceleration
  const bool accelerated = last_bucket_.has_value();
  const Vec3 alpha = accelerated ? Vec3((bucket.omega - last_bucket_->omega) / h) : Vec3::Zero();
  const Vec3 a_origin =
      accelerated ? Vec3((bucket.velocity - last_bucket_->velocity) / h) : Vec3::Zero();
  last_bucket_ = bucket;
  const auto carried = [&](const Vec3& x) {
    return Vec3(bucket.velocity + bucket.omega.cross(x - bucket.position));
  };
  const auto felt_gravity = [&](const Vec3& x) {
    const Vec3 r = x - bucket.position;
    const Vec3 a = a_origin + alpha.cross(r) + bucket.omega.cross(bucket.omega.cross(r));
    return Vec3(pose.orientation.conjugate() * (g - a));
  };
  // the load rests only while the bucket digs nothing: a zone pushes soil into it
  const bool digging = last_.zone.depth > 0.0;
  std::vector<char> held(particles.size(), 0);
  if (!digging)
    for (int k : particles_in_bucket(particles, bucket_mesh_, pose)) held[k] = 1;
  bool changed = false;
  int resting = 0;
  for (size_t k = 0; k < particles.size(); ++k) {
    Rest& r = rest_[k];
    if (r.resting) {
      // where the bucket carries it, with the bucket's motion
      const Vec3 x = pose.to_world(r.local);
      particles.position[k] = x;
      particles.velocity[k] = carried(x);
      particles.omega[k] = bucket.omega;
      changed = true;
      // released there with its own mass (the host copy's) once the bucket digs again or the
      // gravity it feels has changed; else it rides on, fixed
      if (digging || (felt_gravity(x) - r.gravity).norm() > kRestRelease * g.norm()) {
        r = Rest{};
        ++last_.released;
        continue;
      }
      particles.inv_mass[k] = 0.0;
      particles.inv_inertia[k] = 0.0;
      ++resting;
      continue;
    }
    // a held, full-grown particle, slow relative to the bucket for kRestTime
    const Vec3& x = particles.position[k];
    const bool slow = held[k] && ledger_[k] >= sphere_mass(full_[k], rho) &&
                      (particles.velocity[k] - carried(x)).norm() < kRestSpeed;
    r.still = slow ? r.still + h : 0.0;
    if (r.still < kRestTime) continue;
    r.resting = true;
    r.local = pose.to_local(x);
    r.gravity = felt_gravity(x);
    r.inv_mass = particles.inv_mass[k];
    r.inv_inertia = particles.inv_inertia[k];
    particles.inv_mass[k] = 0.0;
    particles.inv_inertia[k] = 0.0;
    particles.velocity[k] = carried(x);
    particles.omega[k] = bucket.omega;
    changed = true;
    ++resting;
  }
  last_.resting = resting;
  return changed;
}

int MultiscaleTerrain::merge(Particles& particles, const KinematicBucket& bucket,
                             std::vector<int>* new_index_of_old) {
  new_index_of_old->assign(particles.size(), -1);
  // the bucket's box, grown by the margin in which nothing merges
  Aabb keep = bucket_scene_.world_bounds(pose_of(bucket));
  keep.lo -= Vec3::Constant(options_.no_merge_margin);
  keep.hi += Vec3::Constant(options_.no_merge_margin);
  std::vector<size_t> kept;  // the particles that stay, in order
  std::vector<double> kept_mass, kept_full;
  std::vector<Rest> kept_rest;
  int merged = 0;
  for (size_t k = 0; k < particles.size(); ++k) {
    const Vec3& x = particles.position[k];
    const double r = particles.radius[k];
    int i = 0, j = 0;
    bool rests = particles.velocity[k].norm() < options_.merge_speed && !keep.contains(x) &&
                 voxels_.column_at(x.x(), x.y(), &i, &j);
    if (rests) {
      const double surface = voxels_.surface_height(i, j);
      // on the surface or on one layer of grains above it, and not in the zone's soil
      rests = x.z() - r <= surface + level_.diameter && !last_.zone.contains(x);
    }
    if (rests) {
      // a column with no room left keeps the particle (the grid's head room is the heap's)
      const double volume = ledger_[k] * options_.soil.swell / voxels_.bank_density();
      const double room = voxels_.nz() * std::pow(voxels_.cell(), 3) - voxels_.column_volume(i, j);
      if (volume > room) rests = false;
    }
    if (rests) {
      voxels_.deposit(i, j, ledger_[k], 1.0 / options_.soil.swell);
      ++merged;
      continue;
    }
    (*new_index_of_old)[k] = static_cast<int>(kept.size());
    kept.push_back(k);
    kept_mass.push_back(ledger_[k]);
    kept_full.push_back(full_[k]);
    kept_rest.push_back(rest_[k]);
  }
  if (merged > 0) {
    particles = particles.permuted(kept);
    ledger_ = std::move(kept_mass);
    full_ = std::move(kept_full);
    rest_ = std::move(kept_rest);
  }
  return merged;
}

int MultiscaleTerrain::grow(Particles& particles) {
  // oldest first, each diameter up by at most the growth step, the last one's share what the
  // pool holds; a particle that reaches its full diameter takes exactly the full mass, so the
  // grown and the spawned-at-full-size particles are alike
  const double rho = options_.particle_material.density;
  const double step = options_.growth_speed * level_.dt;
  int grown = 0;
  for (size_t k = 0; k < particles.size() && pool_ > 0.0; ++k) {
    const double full_mass = sphere_mass(full_[k], rho);
    if (ledger_[k] >= full_mass) continue;
    const double d_now = sphere_diameter(ledger_[k], rho);
    const double d_next = std::min(full_[k], d_now + step);
    const double m_next = d_next >= full_[k] ? full_mass : sphere_mass(d_next, rho);
    // the pool pays the whole step, or what it holds (the branch decided once: a rounded sum
    // ledger + pool equal to m_next must not send the pool below zero)
    const bool whole = m_next - ledger_[k] <= pool_;
    const double m = whole ? m_next : ledger_[k] + pool_;
    if (!(m > ledger_[k])) continue;
    pool_ = whole ? pool_ - (m_next - ledger_[k]) : 0.0;
    ledger_[k] = m;
    particles.resize(k, m == full_mass ? 0.5 * full_[k] : 0.5 * sphere_diameter(m, rho), rho);
    ++grown;
  }
  return grown;
}

int MultiscaleTerrain::spawn(Particles& particles, const std::vector<ExcavatedColumn>& columns,
                             const BucketPose& pose) {
  if (pool_ <= 0.0) return 0;
  const double d = level_.diameter;
  // the sites: the columns this step excavated, or, when it excavated none, the last ones that
  // were (the pool's soil came from there), each from its floor up to kSpawnHeight. The floor is
  // the highest of the column and its four neighbours: a particle (up to 0.55 D across its
  // column's centre) would otherwise start inside a taller neighbour's box at a cut face
  if (!columns.empty()) sites_ = columns;
  // the first seed's size (drawn whether or not it is made: the sequence is the same on every
  // run); a pool that cannot pay for it makes nothing, without the slots and their queries (most
  // steps of a dig: issue 14)
  std::uniform_real_distribution<double> spread(-kSizeSpread, kSizeSpread);
  const double rho = options_.particle_material.density;
  const double fraction = options_.seed_diameter;
  double next_d = d * (1.0 + spread(sizes_));
  if (pool_ < sphere_mass(fraction == 1.0 ? next_d : fraction * next_d, rho)) return 0;
  const auto floor_of = [&](int i, int j) {
    double f = voxels_.surface_height(i, j);
    const int di[4] = {-1, 1, 0, 0}, dj[4] = {0, 0, -1, 1};
    for (int n = 0; n < 4; ++n) {
      const int a = i + di[n], b = j + dj[n];
      if (a >= 0 && a < voxels_.nx() && b >= 0 && b < voxels_.ny())
        f = std::max(f, voxels_.surface_height(a, b));
    }
    return f;
  };
  // the slots, layer by layer over the sites (each site's floor found once): fill the free slots
  // in order with seeds while the pool holds the next one's mass; each seed's full diameter
  // drawn as the particles' sizes always were (a seed of fraction 1 is the full particle, made as
  // before growth existed). The grid holds the particles as they are and the seeds made here at
  // their full size. A layer's slots are made and asked of the bucket only when the pool reaches
  // them (at G50 the pool runs out within a few of the 40 layers; each slot's answer is its own,
  // so the seeds are the same)
  std::vector<double> floors;
  floors.reserve(sites_.size());
  for (const ExcavatedColumn& c : sites_) floors.push_back(floor_of(c.i, c.j));
  CentreGrid grid(d * (1.0 + kSizeSpread));
  for (size_t k = 0; k < particles.size(); ++k)
    grid.add(particles.position[k], particles.radius[k]);
  const int layers = std::max(1, static_cast<int>(kSpawnHeight / d));
  std::vector<int> all(sites_.size());
  for (size_t k = 0; k < all.size(); ++k) all[k] = static_cast<int>(k);
  int made = 0;
  for (int layer = 0; layer < layers; ++layer) {
    Particles slots;
    for (size_t s = 0; s < sites_.size(); ++s)
      slots.add(Vec3(voxels_.column_x(sites_[s].i), voxels_.column_y(sites_[s].j),
                     floors[s] + 0.5 * d * (1.0 + kSizeSpread) + layer * d),
                0.5 * d * (1.0 + kSizeSpread), options_.particle_material.density);
    std::vector<bool> blocked(slots.size(), false);
    for (const BucketContact& c : bucket_scene_.find_bucket_contacts(slots, all, pose, 0.0))
      blocked[c.particle] = true;
    for (size_t k = 0; k < slots.size(); ++k) {
      const double seed_d = fraction == 1.0 ? next_d : fraction * next_d;
      const double mass = sphere_mass(seed_d, rho);
      if (pool_ < mass) return made;
      if (blocked[k]) continue;
      const Vec3 x = slots.position[k];
      // the seed's slot must hold its full size: a seed placed in a gap its full size does not
      // fit overfills the zone as it grows (docs/multiscale.md "Growth": measured)
      if (grid.touches(x, 0.5 * next_d)) continue;
      particles.add(x, 0.5 * seed_d, rho);
      ledger_.push_back(mass);
      full_.push_back(next_d);
      rest_.emplace_back();
      pool_ -= mass;
      grid.add(x, 0.5 * next_d);
      ++made;
      next_d = d * (1.0 + spread(sizes_));
    }
  }
  // a draw for a particle not made is dropped; the sequence, so every size, is the same on every
  // run
  return made;
}

std::vector<double> MultiscaleTerrain::soil_surface(const Particles& particles,
                                                    const std::vector<char>& held) const {
  std::vector<double> surface = voxels_.surface_heights();
  // a particle raises its column to its top if it rests on the soil there, within a cell of the
  // surface found so far (bottom up): the heap in front of a tool counts, a grain in flight does
  // not, nor one the bucket holds (a cell is coarser than the bucket's floor, so its load would
  // otherwise stack on the heap under it)
  const int nx = voxels_.nx();
  // (column, bottom, top) of each particle, sorted: by column, then bottom up (one flat list:
  // a list per column cost an allocation per occupied column, every step)
  std::vector<std::tuple<size_t, double, double>> spans;
  spans.reserve(particles.size());
  for (size_t k = 0; k < particles.size(); ++k) {
    if (held[k]) continue;
    int i = 0, j = 0;
    if (!voxels_.column_at(particles.position[k].x(), particles.position[k].y(), &i, &j)) continue;
    const double r = particles.radius[k];
    spans.emplace_back(static_cast<size_t>(j) * nx + i, particles.position[k].z() - r,
                       particles.position[k].z() + r);
  }
  std::sort(spans.begin(), spans.end());
  for (const auto& [c, bottom, top] : spans)
    if (bottom <= surface[c] + voxels_.cell()) surface[c] = std::max(surface[c], top);
  return surface;
}

std::vector<StaticGeom> MultiscaleTerrain::geometry(const Particles& particles) const {
  std::vector<StaticGeom> geoms = pile_container(profile_);
  if (particles.size() == 0) return geoms;
  // the columns under the particles' box, grown by a particle: each a box up to its surface
  const auto [lo, hi] = centres_box(particles);
  const double grow = 2.0 * level_.diameter;
  const double h = voxels_.cell();
  const int i0 = std::max(0, static_cast<int>(std::floor((lo.x() - grow - voxels_.x0()) / h)));
  const int i1 =
      std::min(voxels_.nx() - 1, static_cast<int>(std::floor((hi.x() + grow - voxels_.x0()) / h)));
  const int j0 = std::max(0, static_cast<int>(std::floor((lo.y() - grow - voxels_.y0()) / h)));
  const int j1 =
      std::min(voxels_.ny() - 1, static_cast<int>(std::floor((hi.y() + grow - voxels_.y0()) / h)));
  PlaneFloorColumn floor;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      double top = voxels_.surface_height(i, j);
      // under the active zone the failure plane itself is the floor, not its columns' staircase
      // (terrain/active_zone failure_plane_column): the column lowered under a plate on the plane
      if (options_.failure_plane_floor && failure_plane_column(last_.zone, voxels_, i, j, &floor)) {
        top = floor.top;
        geoms.push_back(floor.plate);
      }
      if (top <= voxels_.z0()) continue;  // bare ground: the ground plane holds them
      const double bottom = voxels_.z0();
      geoms.push_back(StaticGeom::box(
          Vec3(voxels_.column_x(i), voxels_.column_y(j), 0.5 * (bottom + top)),
          Vec3(0.5 * h, 0.5 * h, 0.5 * (top - bottom)), Eigen::Matrix3d::Identity()));
    }
  return geoms;
}

namespace {
// the zone's fields, in their declaration order
void write_zone(ByteWriter& w, const ActiveZone& z) {
  w.u8(z.active ? 1 : 0);
  write_matrix(w, z.tip);
  write_matrix(w, z.along);
  write_matrix(w, z.forward);
  for (double v :
       {z.width, z.depth, z.speed, z.rake_deg, z.failure_angle_deg, z.reach_ahead, z.reach_behind})
    w.f64(v);
}
ActiveZone read_zone(ByteReader& r) {
  ActiveZone z;
  z.active = r.u8("active zone") != 0;
  read_matrix(r, z.tip, "active zone");
  read_matrix(r, z.along, "active zone");
  read_matrix(r, z.forward, "active zone");
  for (double* v : {&z.width, &z.depth, &z.speed, &z.rake_deg, &z.failure_angle_deg, &z.reach_ahead,
                    &z.reach_behind})
    *v = r.f64("active zone");
  // what predict_active_zone guarantees: an edge of at least 1 mm, unit directions, finite values
  bool ok = z.width >= 1e-3 && z.tip.allFinite() && std::abs(z.along.norm() - 1.0) < 1e-9 &&
            std::abs(z.forward.norm() - 1.0) < 1e-9;
  for (double v :
       {z.width, z.depth, z.speed, z.rake_deg, z.failure_angle_deg, z.reach_ahead, z.reach_behind})
    ok = ok && std::isfinite(v);
  if (!ok) throw InputError(r.where() + ": the last step's active zone is not one (corrupt)");
  return z;
}
}  // namespace

void MultiscaleTerrain::save_state(ByteWriter& w) const {
  w.tag("voxels");
  voxels_.save_state(w);
  w.tag("zone particles");
  dem_->save_state(w);
  tools_->save_state(w);
  w.u64(ledger_.size());
  w.f64s(ledger_.data(), ledger_.size());
  w.f64s(full_.data(), full_.size());
  w.f64(pool_);
  w.u64(sites_.size());
  for (const ExcavatedColumn& c : sites_) {
    w.i64(c.i);
    w.i64(c.j);
    w.f64(c.z_lo);
    w.f64(c.z_hi);
    w.f64(c.mass);
  }
  // the generator's whole state, as the standard library writes it (decimal words)
  std::ostringstream generator;
  generator.imbue(std::locale::classic());  // the same bytes whatever locale the program set
  generator << sizes_;
  w.str(generator.str());
  w.f64(time_);
  w.tag("last step");
  write_zone(w, last_.zone);
  w.f64(last_.excavated);
  w.i64(last_.spawned);
  w.i64(last_.grown);
  w.i64(last_.merged);
  w.f64(last_.avalanched);
  write_matrix(w, last_.bucket_wrench);
  // the bucket's resting load (rest_in_bucket): each particle's rest, the bucket's last motion
  w.tag("resting load");
  w.u8(options_.rest_in_bucket ? 1 : 0);
  if (!options_.rest_in_bucket) return;
  w.i64(last_.resting);
  w.i64(last_.released);
  for (const Rest& rest : rest_) {
    w.f64(rest.still);
    w.u8(rest.resting ? 1 : 0);
    write_matrix(w, rest.local);
    write_matrix(w, rest.gravity);
    w.f64(rest.inv_mass);
    w.f64(rest.inv_inertia);
  }
  w.u8(last_bucket_ ? 1 : 0);
  if (last_bucket_) {
    write_matrix(w, last_bucket_->position);
    write_matrix(w, last_bucket_->orientation.coeffs());
    write_matrix(w, last_bucket_->velocity);
    write_matrix(w, last_bucket_->omega);
  }
}

void MultiscaleTerrain::restore_state(ByteReader& r) {
  r.expect("voxels");
  voxels_.restore_state(r);
  r.expect("zone particles");
  dem_->restore_state(r, true);
  tools_->restore_state(r);
  const std::uint64_t n = r.u64("particle masses");
  r.need_elements(n, 16, "particle masses");  // each particle's mass and full diameter
  if (n != dem_->size())
    throw InputError(r.where() + ": " + std::to_string(n) + " particle masses for " +
                     std::to_string(dem_->size()) + " particles (corrupt)");
  std::vector<double> ledger(n), full(n);
  r.f64s(ledger.data(), ledger.size(), "particle masses");
  r.f64s(full.data(), full.size(), "full diameters");
  const double pool = r.f64("pool");
  const std::uint64_t sites = r.u64("excavated columns");
  r.need_elements(sites, 8 * 5, "excavated columns");
  std::vector<ExcavatedColumn> columns(sites);
  for (ExcavatedColumn& c : columns) {
    const std::int64_t i = r.i64("excavated columns"), j = r.i64("excavated columns");
    if (i < 0 || i >= voxels_.nx() || j < 0 || j >= voxels_.ny())
      throw InputError(r.where() + ": an excavated column outside the grid (corrupt)");
    c.i = static_cast<int>(i);
    c.j = static_cast<int>(j);
    c.z_lo = r.f64("excavated columns");
    c.z_hi = r.f64("excavated columns");
    c.mass = r.f64("excavated columns");
  }
  std::istringstream generator(r.str("size generator"));
  generator.imbue(std::locale::classic());
  std::mt19937_64 sizes;
  generator >> sizes;
  if (generator.fail())
    throw InputError(r.where() + ": the particle-size generator's state does not read (corrupt)");
  for (double m : ledger)
    if (!(m > 0.0 && std::isfinite(m)))
      throw InputError(r.where() + ": a particle mass of " + std::to_string(m) + " kg (corrupt)");
  for (size_t k = 0; k < n; ++k) {
    // a particle holds at most its full size's mass (a growing seed less)
    if (!(full[k] > 0.0 && std::isfinite(full[k])) ||
        ledger[k] > sphere_mass(full[k], options_.particle_material.density))
      throw InputError(r.where() + ": a full particle diameter of " + std::to_string(full[k]) +
                       " m for a mass of " + std::to_string(ledger[k]) + " kg (corrupt)");
  }
  if (!(pool >= 0.0 && std::isfinite(pool)))
    throw InputError(r.where() + ": a pool of " + std::to_string(pool) + " kg (corrupt)");
  const double time = r.f64("terrain clock");
  r.expect("last step");
  MultiscaleStep last;
  last.zone = read_zone(r);
  last.excavated = r.f64("last step");
  const std::int64_t spawned = r.i64("last step"), grown = r.i64("last step"),
                     merged = r.i64("last step");
  if (spawned < 0 || spawned > static_cast<std::int64_t>(n) || grown < 0 ||
      grown > static_cast<std::int64_t>(n) || merged < 0 ||
      merged > std::numeric_limits<int>::max())
    throw InputError(r.where() + ": the last step spawned " + std::to_string(spawned) + ", grew " +
                     std::to_string(grown) + " and merged " + std::to_string(merged) +
                     " particles (corrupt)");
  last.spawned = static_cast<int>(spawned);
  last.grown = static_cast<int>(grown);
  last.merged = static_cast<int>(merged);
  last.avalanched = r.f64("last step");
  read_matrix(r, last.bucket_wrench, "last step");
  // the bucket's resting load, saved by a terrain with the same study option
  r.expect("resting load");
  const bool riding = r.u8("resting load") != 0;
  if (riding != options_.rest_in_bucket)
    throw InputError(r.where() + ": saved by a type-G terrain with the bucket's resting load " +
                     (riding ? "riding" : "in the DEM") + " (rest_in_bucket " +
                     (riding ? "on" : "off") + "), restored into one with it " +
                     (options_.rest_in_bucket ? "on" : "off") +
                     "; restore with the option it was saved with");
  std::vector<Rest> rest(n);
  std::optional<KinematicBucket> last_bucket;
  if (riding) {
    const std::int64_t resting = r.i64("resting load"), released = r.i64("resting load");
    if (resting < 0 || resting > static_cast<std::int64_t>(n) || released < 0 ||
        released > std::numeric_limits<int>::max())
      throw InputError(r.where() + ": " + std::to_string(resting) + " particles riding and " +
                       std::to_string(released) + " released (corrupt)");
    last.resting = static_cast<int>(resting);
    last.released = static_cast<int>(released);
    r.need_elements(n, 8 + 1 + 8 * 6 + 8 + 8, "resting load");
    for (Rest& rest_k : rest) {
      rest_k.still = r.f64("resting load");
      rest_k.resting = r.u8("resting load") != 0;
      read_matrix(r, rest_k.local, "resting load");
      read_matrix(r, rest_k.gravity, "resting load");
      rest_k.inv_mass = r.f64("resting load");
      rest_k.inv_inertia = r.f64("resting load");
      // a riding particle's own mass, kept while the device holds it fixed
      if (!(rest_k.still >= 0.0 && std::isfinite(rest_k.still)) ||
          (rest_k.resting && !(rest_k.inv_mass > 0.0 && rest_k.inv_inertia > 0.0)) ||
          !rest_k.local.allFinite() || !rest_k.gravity.allFinite())
        throw InputError(r.where() + ": a riding particle's rest that does not read (corrupt)");
    }
    if (r.u8("resting load") != 0) {
      KinematicBucket b;
      Eigen::Vector4d q;
      read_matrix(r, b.position, "resting load");
      read_matrix(r, q, "resting load");
      read_matrix(r, b.velocity, "resting load");
      read_matrix(r, b.omega, "resting load");
      if (!(std::abs(q.norm() - 1.0) < 1e-9))
        throw InputError(r.where() +
                         ": the bucket's last orientation is not a unit quaternion "
                         "(corrupt)");
      b.orientation.coeffs() = q;
      last_bucket = b;
    }
  }
  ledger_ = std::move(ledger);
  full_ = std::move(full);
  rest_ = std::move(rest);
  last_bucket_ = last_bucket;
  pool_ = pool;
  sites_ = std::move(columns);
  sizes_ = sizes;
  time_ = time;
  last_ = last;
  // the host copy every reader uses, as the step leaves it
  download_particles();
}

}  // namespace talus
