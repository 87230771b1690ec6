#include "solvers/tool_world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "host/error.hpp"
#include "host/stage_times.hpp"

namespace talus {

void add_box(vehicle::BucketMesh& mesh, const Vec3& centre, const Vec3& half) {
  const int base = static_cast<int>(mesh.vertices.size());
  // corners: bit 0 of k picks +x, bit 1 +y, bit 2 +z
  for (int k = 0; k < 8; ++k)
    mesh.vertices.push_back(centre + Vec3((k & 1) ? half.x() : -half.x(), (k & 2) ? half.y() : -half.y(),
                                          (k & 4) ? half.z() : -half.z()));
  // two triangles per face, wound counter-clockwise seen from outside
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    mesh.triangles.push_back({base + f[0], base + f[1], base + f[2]});
    mesh.triangles.push_back({base + f[0], base + f[2], base + f[3]});
  }
}

// one tool's device side and its warm-start memory
struct ToolWorld::Side {
  Side(Device& dev, Tool t, const embree::Device& embree)
      : tool(std::move(t)), scene(tool.mesh, embree), selection(dev), block(dev) {
    for (const Vec3& v : tool.mesh.vertices) reach = std::max(reach, v.norm());
  }
  Tool tool;
  double reach = 0.0;  // the farthest vertex from the frame's origin [m]
  BucketScene scene;
  DeviceBoxSelection selection;
  BucketRowBlock block;
  // this step's rows, their contacts and candidates; last step's impulses for the warm start
  std::vector<ContactRow> rows;
  std::vector<int> candidates;
  std::vector<BucketImpulse> previous;
  ToolLoad load;
};

ToolWorld::ToolWorld(Device& dev, DemWorld& dem, std::vector<Tool> tools,
                     const embree::Device& embree)
    : dev_(dev), dem_(dem), kinematic_(std::make_unique<KinematicToolRows>(dev)) {
  for (size_t i = 0; i < tools.size(); ++i) {
    const Tool& t = tools[i];
    const std::string field = "tool " + std::to_string(i);
    if (!(t.material.friction >= 0.0) || !(t.material.rolling >= 0.0))
      throw InputError(field + ": friction and rolling must not be negative");
    if (!t.mobility.bottomRows<3>().isZero(0.0) || !t.mobility.topRightCorner<3, 3>().isZero(0.0))
      throw InputError(field + ": mobility turns the tool or moves it with torques; tools translate only (angular rows and "
                       "the top-right block must be zero)");
    if (!t.mobility.isZero(0.0) && !t.omega.isZero(0.0))
      throw InputError(field +
                       ": a loaded tool (non-zero mobility) cannot have a prescribed omega; only a "
                       "kinematic tool "
                       "turns");
    sides_.push_back(std::make_unique<Side>(dev, t, embree));
  }
}

ToolWorld::~ToolWorld() = default;

void ToolWorld::renumber_particles(const std::vector<int>& new_index_of_old) {
  // a monotone numbering keeps each list sorted by particle, as the matching needs
  for (auto& side : sides_) {
    std::vector<BucketImpulse> kept;
    for (BucketImpulse impulse : side->previous) {
      const int index =
          impulse.particle >= 0 && static_cast<size_t>(impulse.particle) < new_index_of_old.size()
              ? new_index_of_old[impulse.particle]
              : -1;
      if (index < 0) continue;
      impulse.particle = index;
      kept.push_back(impulse);
    }
    side->previous = std::move(kept);
  }
}

void ToolWorld::save_state(ByteWriter& w) const {
  w.u64(sides_.size());
  for (const auto& side : sides_) {
    const Tool& t = side->tool;
    write_matrix(w, t.position);
    write_matrix(w, t.orientation.coeffs());
    write_matrix(w, t.velocity);
    write_matrix(w, t.omega);
    write_bucket_impulses(w, side->previous);
    write_matrix(w, side->load.wrench);
    w.i64(side->load.contacts);
    w.f64(side->load.max_overlap_rel);
  }
}

void ToolWorld::restore_state(ByteReader& r) {
  const std::uint64_t n = r.u64("tools");
  if (n != sides_.size())
    throw InputError(r.where() + ": the saved state has " + std::to_string(n) +
                     " tools, this world " + std::to_string(sides_.size()));
  // everything read first, then the world changed: a bad entry leaves it as it was
  struct Saved {
    Vec3 position, velocity, omega;
    Eigen::Vector4d rotation;
    std::vector<BucketImpulse> previous;
    ToolLoad load;
  };
  std::vector<Saved> saved(n);
  for (Saved& s : saved) {
    read_matrix(r, s.position, "tool pose");
    read_matrix(r, s.rotation, "tool pose");
    read_matrix(r, s.velocity, "tool twist");
    read_matrix(r, s.omega, "tool twist");
    s.previous = read_bucket_impulses(r, dem_.size());
    read_matrix(r, s.load.wrench, "tool load");
    const std::int64_t contacts = r.i64("tool load");
    if (contacts < 0 || contacts > std::numeric_limits<int>::max())
      throw InputError(r.where() + ": a tool with " + std::to_string(contacts) +
                       " contacts (corrupt)");
    s.load.contacts = static_cast<int>(contacts);
    s.load.max_overlap_rel = r.f64("tool load");
    if (!(std::abs(s.rotation.norm() - 1.0) < 1e-9))
      throw InputError(r.where() + ": a tool's orientation is not a unit quaternion (corrupt)");
  }
  for (size_t i = 0; i < n; ++i) {
    Tool& t = sides_[i]->tool;
    t.position = saved[i].position;
    t.orientation.coeffs() = saved[i].rotation;
    t.velocity = saved[i].velocity;
    t.omega = saved[i].omega;
    sides_[i]->previous = std::move(saved[i].previous);
    sides_[i]->load = saved[i].load;
  }
}

size_t ToolWorld::size() const { return sides_.size(); }
Tool& ToolWorld::tool(size_t i) { return sides_.at(i)->tool; }
const Tool& ToolWorld::tool(size_t i) const { return sides_.at(i)->tool; }
const ToolLoad& ToolWorld::load(size_t i) const { return sides_.at(i)->load; }

void ToolWorld::step() {
  const double h = dem_.settings().dt;
  dem_.begin_step();
  const StepParams params = from_device(dem_.params());
  const double r_max = dem_.max_radius();

  // kinematic tools only (the type-G bucket, the blade, the ring): their rows are solved a
  // particle at a time inside the particle sweeps (solvers/kinematic_tool_rows, the serial walk's
  // bits); a loaded tool moves with its rows, so they are one chain per tool (BucketRowBlock)
  const bool kinematic = std::all_of(sides_.begin(), sides_.end(), [](const auto& side) {
    return side->tool.mobility.isZero(0.0);
  });
  std::vector<std::vector<TlRow>> kinematic_rows;
  std::vector<BucketBody> kinematic_bodies;

  // each tool: candidates near it, their contacts, rows warm-started from last step's impulses
  for (auto& side : sides_) {
    Tool& t = side->tool;
    side->load = ToolLoad{};
    side->rows.clear();
    side->candidates.clear();
    BucketPose pose;
    pose.position = t.position;
    pose.orientation = t.orientation;
    // what the tool and a particle can close within the step is covered by speculative rows
    const double tool_speed = t.velocity.norm() + t.omega.norm() * side->reach;
    const double reach = 2.0 * h * (tool_speed + dem_.settings().max_speed);
    std::vector<BucketContact> contacts;
    Particles near;
    if (dem_.size() > 0) {
      const double margin_box = dem_.settings().margin_rel + reach / std::max(r_max, 1e-12);
      const Aabb box = candidate_box(side->scene.world_bounds(pose), r_max, margin_box);
      DemBuffers& b = dem_.buffers();
      side->candidates = side->selection.select(b.position, dem_.size(), box);
      near = side->block.gather(side->candidates, b.position, b.velocity, b.omega);
      // fixed particles (zero inverse mass: the type-G bucket's resting load, which rides with
      // it) get no rows with a kinematic tool: two bodies that cannot move against each other (a
      // loaded tool still meets them, as it meets any fixed particle)
      const bool fixed_tool = t.mobility.isZero(0.0);
      std::vector<int> local;
      local.reserve(side->candidates.size());
      for (size_t k = 0; k < side->candidates.size(); ++k)
        if (!fixed_tool || near.inv_mass[k] > 0.0) local.push_back(static_cast<int>(k));
      double r_min = r_max;
      for (double r : near.radius) r_min = std::min(r_min, r);
      const double margin = dem_.settings().margin_rel + reach / std::max(r_min, 1e-12);
      contacts = side->scene.find_bucket_contacts(near, local, pose, margin);
    }
    side->load.contacts = static_cast<int>(contacts.size());
    for (const BucketContact& c : contacts)
      side->load.max_overlap_rel = std::max(side->load.max_overlap_rel, -c.gap / near.radius[c.particle]);

    std::vector<BucketContact> keyed = contacts;
    for (auto& c : keyed) c.particle = side->candidates[c.particle];
    const std::vector<int> match = dem_.settings().warm_start ? match_bucket_contacts(keyed, side->previous)
                                                              : std::vector<int>();
    BucketBody body;
    body.velocity = t.velocity;
    body.omega = t.omega;
    body.mobility = t.mobility;
    side->rows = make_bucket_rows(contacts, near, body, t.position, params, t.material, side->previous, match);
    set_bucket_effective_masses(side->rows, contacts, near, t.mobility);
    // a loaded tool starts the sweeps from its velocity after its external force and the
    // warm-start impulses (as the bucket starts from the vehicle solved under them)
    Vec6 push = bucket_wrench_impulse(side->rows);
    push.head<3>() += h * t.external_force;
    body.velocity += (t.mobility * push).head<3>();
    std::vector<TlRow> device_rows;
    device_rows.reserve(side->rows.size());
    for (const auto& r : side->rows) {
      TlRow d = to_device(r);
      d.a = side->candidates[r.a];
      device_rows.push_back(d);
    }
    if (kinematic) {
      kinematic_rows.push_back(std::move(device_rows));
      kinematic_bodies.push_back(body);
    } else {
      side->block.set_rows(device_rows);
      side->block.set_bucket(body);
    }
  }
  if (kinematic) kinematic_->set(kinematic_rows, kinematic_bodies);

  // velocities: gravity, warm starts, then every sweep over the particle rows and each tool's
  // (each a stage of a profiled run, as in the coupled type-D step: solvers/split_solver)
  Device& dev = dem_.device();
  {
    StageScope stage(dev, "warm_start");
    dem_.apply_gravity();
    dem_.warm_start();
    if (dem_.settings().warm_start) {
      if (kinematic)
        kinematic_->warm_start(dem_.buffers().velocity, dem_.buffers().omega);
      else
        for (auto& side : sides_)
          side->block.warm_start(dem_.buffers().velocity, dem_.buffers().omega);
    }
  }
  if (kinematic) {
    // the tools' rows inside the particle sweeps (their stage)
    StageScope stage(dev, "particle_sweeps");
    dem_.sweep_fixed_with_tools(dem_.settings().iterations, *kinematic_);
  } else {
    for (int it = 0; it < dem_.settings().iterations; ++it) {
      {
        StageScope stage(dev, "particle_sweeps");
        dem_.sweep_fixed(1);
      }
      StageScope stage(dev, "bucket_rows");
      for (auto& side : sides_) side->block.sweep(dem_.buffers().velocity, dem_.buffers().omega);
    }
  }

  // the tools' loads and (loaded tools) their new velocities; impulses kept for the warm start
  const std::vector<std::vector<TlRow>> kinematic_solved =
      kinematic ? kinematic_->solved() : std::vector<std::vector<TlRow>>();
  for (size_t i = 0; i < sides_.size(); ++i) {
    Side* side = sides_[i].get();
    Tool& t = side->tool;
    if (!side->rows.empty()) {
      const std::vector<TlRow> solved = kinematic ? kinematic_solved[i] : side->block.rows();
      for (size_t k = 0; k < side->rows.size(); ++k) {
        const ContactRow r = from_device(solved[k]);
        side->rows[k].impulse_n = r.impulse_n;
        side->rows[k].impulse_t = r.impulse_t;
        side->rows[k].impulse_r = r.impulse_r;
      }
    }
    side->load.wrench = bucket_wrench_impulse(side->rows) / h;
    if (!t.mobility.isZero(0.0)) t.velocity = side->block.bucket().velocity;
    side->previous = bucket_impulses(side->rows, side->candidates);
    std::stable_sort(side->previous.begin(), side->previous.end(),
                     [](const BucketImpulse& a, const BucketImpulse& b) { return a.particle < b.particle; });
  }
  dem_.end_step();
  // the tools move: translation, and the prescribed turn as the rotation by h omega
  for (auto& side : sides_) {
    Tool& t = side->tool;
    t.position += h * t.velocity;
    const double angle = h * t.omega.norm();
    if (angle > 0.0)
      t.orientation = (Eigen::AngleAxisd(angle, t.omega.normalized()) * t.orientation).normalized();
  }
}

}  // namespace talus
