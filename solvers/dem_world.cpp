#include "solvers/dem_world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "host/stage_times.hpp"
#include "solvers/tolerance_schedule.hpp"

namespace talus {

namespace {
// must equal COLOUR_BLOCK in kernels/colouring.cl
constexpr int kColourBlock = 256;
// a grid larger than this many cells means the bounds are far too big for the particles
constexpr double kMaxGridCells = 64.0e6;
// Jones-Plassmann rounds launched between two looks at the colouring's status: each look is a
// host round trip (a wait for the queue), which cost D400 steps as much as their sweeps; rounds
// after the last contact is coloured change nothing, so at most this many minus one are spare
constexpr int kColourRoundsPerCheck = 4;
// rows whose squared residuals one work-item of sum_residual_blocks adds up: the host downloads
// 2 n_rows / 256 floats (15,000 at D50) instead of n_rows, and the sum's order depends on this
// alone
constexpr int kResidualBlock = 256;
}  // namespace

TlGeom to_device(const StaticGeom& g) {
  TlGeom d{};
  d.centre = to_float4(g.centre, 0.0);
  d.axis_x = to_float4(g.axes.col(0), 0.0);
  d.axis_y = to_float4(g.axes.col(1), 0.0);
  d.axis_z = to_float4(g.axes.col(2), 0.0);
  d.half_extent = to_float4(g.half, 0.0);
  d.type = g.type == StaticGeom::Type::Plane ? TL_GEOM_PLANE : TL_GEOM_BOX;
  return d;
}

DemWorld::DemWorld(Device& dev, const Material& material, const DemSettings& settings,
                   const Bounds& bounds, std::vector<StaticGeom> geoms)
    : dev_(dev),
      material_(material),
      settings_(settings),
      bounds_(bounds),
      geoms_(std::move(geoms)),
      buffers_(dev),
      scan_(dev),
      sweep_kind_(settings.sweep),
      sweep_one_group_rows_(settings.one_group_rows) {
  if (!(settings.dt > 0.0)) throw InputError("DemSettings.dt: the timestep must be positive");
  if (!(settings.overlap_floor_rel > 0.0))
    throw InputError("DemSettings.overlap_floor_rel: must be positive (it keeps the compliance finite)");
  if (!(settings.margin_rel >= 0.0)) throw InputError("DemSettings.margin_rel: must not be negative");
  if (!(material.poisson >= 0.0 && material.poisson < 0.5))
    throw InputError("Material.poisson: must lie in [0, 0.5)");
  if (settings.iterations < 1) throw InputError("DemSettings.iterations: must be at least 1");
  if (!(material.young > 0.0) || !(material.density > 0.0))
    throw InputError("Material: young and density must be positive");
  if ((bounds.hi - bounds.lo).minCoeff() <= 0.0)
    throw InputError("Bounds: hi must exceed lo on every axis");

  // kernels of every stage (each program is built once per device and cached by PoCL)
  const cl::Program& broad = dev.program({"dem_common.cl", "broadphase.cl"});
  k_cell_count_ = dev.kernel(broad, "cell_count");
  k_cell_fill_ = dev.kernel(broad, "cell_fill");
  k_cell_sort_ = dev.kernel(broad, "cell_sort");
  const cl::Program& narrow = dev.program({"dem_common.cl", "narrowphase.cl"});
  k_contact_count_ = dev.kernel(narrow, "contact_count");
  k_contact_write_ = dev.kernel(narrow, "contact_write");
  k_adj_count_ = dev.kernel(narrow, "adjacency_count");
  k_adj_fill_ = dev.kernel(narrow, "adjacency_fill");
  k_adj_sort_ = dev.kernel(narrow, "adjacency_sort");
  const cl::Program& colour = dev.program({"dem_common.cl", "colouring.cl"});
  k_colour_round_ = dev.kernel(colour, "colour_round");
  k_colour_hist_ = dev.kernel(colour, "colour_histogram");
  k_colour_scatter_ = dev.kernel(colour, "colour_scatter");
  k_colour_ranges_ = dev.kernel(colour, "colour_ranges");
  k_identity_ = dev.kernel(colour, "identity_order");
  k_interleaved_ = dev.kernel(colour, "interleaved_order");
  k_contact_part_ = dev.kernel(colour, "contact_part");
  k_interleave_runs_ = dev.kernel(colour, "interleave_runs");
  k_pairs_differ_ = dev.kernel(colour, "contact_pairs_differ");
  k_carry_colours_ = dev.kernel(colour, "carry_colours");
  k_drop_conflicts_ = dev.kernel(colour, "drop_colour_conflicts");
  const cl::Program& solver = dev.program(kSolverProgram);
  k_prepare_ = dev.kernel(solver, "prepare_rows");
  k_gravity_ = dev.kernel(solver, "apply_gravity");
  k_apply_impulses_ = dev.kernel(solver, "apply_row_impulses");
  k_store_ = dev.kernel(solver, "store_impulses");
  k_integrate_ = dev.kernel(solver, "integrate");
  k_residual_ = dev.kernel(solver, "row_residual");
  k_sum_blocks_ = dev.kernel(solver, "sum_residual_blocks");
  k_first_non_finite_ = dev.kernel(solver, "first_non_finite");

  set_geoms(geoms_);
}

void DemWorld::set_material(const Material& material) {
  material_ = material;
  update_params();
}

void DemWorld::set_grid_region(const std::optional<Bounds>& region) {
  if (region && !(region->lo.allFinite() && region->hi.allFinite() &&
                  (region->lo.array() <= region->hi.array()).all()))
    throw Error("DemWorld::set_grid_region: the region must be a finite box with lo <= hi");
  // a grid refused (too many cells) leaves the world with the region it had
  const std::optional<Bounds> before = grid_region_;
  grid_region_ = region;
  try {
    update_params();
  } catch (...) {
    grid_region_ = before;
    update_params();
    throw;
  }
}

void DemWorld::set_geoms(std::vector<StaticGeom> geoms, GeomChange change) {
  geoms_ = std::move(geoms);
  ++geoms_version_;
  std::vector<TlGeom> g;
  for (auto& s : geoms_) g.push_back(to_device(s));
  if (g.empty()) g.push_back(TlGeom{});  // keep the buffer non-empty; params.geoms stays 0
  buffers_.geoms.upload(g);
  // static contacts match by geometry index
  if (change == GeomChange::Replaced) buffers_.has_previous = false;
  if (change != GeomChange::Moved) buffers_.static_previous = false;
  update_params();
}

void DemWorld::update_params() {
  // the settings a caller may have changed through settings(), checked before the params change
  check_relaxation(settings_.relaxation, settings_.sweep, "DemSettings.relaxation");
  if (!(settings_.tolerance >= 0.0) || !std::isfinite(settings_.tolerance))
    throw InputError(
        "DemSettings.tolerance: must be finite and not negative [m/s]; use 0 for no "
        "early stop");
  if (settings_.narrow_phase_slots < 0 || settings_.narrow_phase_slots > kMaxNarrowPhaseSlots)
    throw InputError(
        "DemSettings.narrow_phase_slots: " + std::to_string(settings_.narrow_phase_slots) +
        " is outside 0-" + std::to_string(kMaxNarrowPhaseSlots) + "; use " +
        std::to_string(kNarrowPhaseSlots) + " (the default)");
  if (settings_.serial_lanes < 0 || settings_.serial_lanes > kMaxSerialLanes)
    throw InputError("DemSettings.serial_lanes: " + std::to_string(settings_.serial_lanes) +
                     " is outside 0-" + std::to_string(kMaxSerialLanes) + "; use " +
                     std::to_string(kSerialLanes) + " (the default) or 0 for colours");
  if (settings_.sweep_parts < 0 || settings_.sweep_parts > kMaxSweepParts)
    throw InputError("DemSettings.sweep_parts: " + std::to_string(settings_.sweep_parts) +
                     " is outside 0-" + std::to_string(kMaxSweepParts) +
                     "; use 0 (the default: one per compute unit)");
  TlStepParams& p = params_;
  p = TlStepParams{};
  p.gravity = to_float4(settings_.gravity, 0.0);
  // grid cells hold the largest pair within the contact margin
  // (before particles arrive, one cell spans the bounds)
  Vec3 extent = bounds_.hi - bounds_.lo;
  double speculative = 2.0 * settings_.dt * settings_.max_speed;
  double cell = particle_count_ > 0 ? 2.0 * max_radius_ * (1.0 + settings_.margin_rel) + speculative
                                    : extent.maxCoeff();
  Eigen::Vector3i dims = (extent / cell).array().ceil().cast<int>().cwiseMax(1);
  p.grid_origin = to_float4(bounds_.lo, 0.0);
  p.cell_size = static_cast<float>(cell);
  // the grid: the bounds' whole lattice, or the cells of it that hold the grid region grown by a
  // cell each way (set_grid_region; the region is the caller's in double, the kernels place a
  // particle in float: a cell to spare holds it where the two round apart)
  Eigen::Vector3i first = Eigen::Vector3i::Zero(), count = dims;
  if (grid_region_ && particle_count_ > 0) {
    const Vec3 origin = xyz(p.grid_origin);
    const double cell_f = p.cell_size;
    const auto lattice = [&](double x, int axis) {
      const double c = std::floor((x - origin[axis]) / cell_f);
      return static_cast<int>(std::clamp(c, 0.0, double(dims[axis] - 1)));
    };
    for (int axis = 0; axis < 3; ++axis) {
      first[axis] = std::max(0, lattice(grid_region_->lo[axis], axis) - 1);
      const int last = std::min(dims[axis] - 1, lattice(grid_region_->hi[axis], axis) + 1);
      count[axis] = std::max(1, last - first[axis] + 1);
    }
  }
  double cells = double(count.x()) * count.y() * count.z();
  if (cells > kMaxGridCells)
    throw InputError("Bounds: the broad-phase grid would have " + std::to_string(cells) +
                     (grid_region_
                          ? " cells over the grid region; shrink the region"
                          : " cells; shrink the bounds to the region particles can reach"));
  p.grid_nx = count.x();
  p.grid_ny = count.y();
  p.grid_nz = count.z();
  p.grid_i0 = first.x();
  p.grid_j0 = first.y();
  p.grid_k0 = first.z();
  p.dt = static_cast<float>(settings_.dt);
  p.young = static_cast<float>(material_.young);
  p.poisson = static_cast<float>(material_.poisson);
  p.friction = static_cast<float>(material_.friction);
  p.rolling = static_cast<float>(material_.rolling);
  p.ground_rolling = static_cast<float>(material_.ground_rolling);
  p.damping_tau = static_cast<float>(material_.damping_steps * settings_.dt);
  p.margin_rel = static_cast<float>(settings_.margin_rel);
  p.overlap_floor_rel = static_cast<float>(settings_.overlap_floor_rel);
  p.particles = static_cast<int>(particle_count_);
  p.geoms = static_cast<int>(geoms_.size());
  p.speculative = static_cast<float>(speculative);
  p.pair_reach = settings_.pair_reach ? 1 : 0;
  p.relaxation = static_cast<float>(settings_.relaxation);
  p.cohesion = static_cast<float>(kRumpfPerR2 * material_.cohesion);
  if (!sweep_ || sweep_kind_ != settings_.sweep ||
      sweep_one_group_rows_ != settings_.one_group_rows) {
    sweep_kind_ = settings_.sweep;
    sweep_one_group_rows_ = settings_.one_group_rows;
    sweep_ = make_sweep(settings_, dev_, p.particles);
  }
}

void DemWorld::bin_geoms() {
  const TlStepParams& p = params_;
  const int nx = p.grid_nx, ny = p.grid_ny;
  // the lists on the device are those of this geometry and these columns already
  const GeomBinning key{geoms_version_, p.cell_size, p.grid_origin.s[0], p.grid_origin.s[1], nx, ny,
                        p.grid_i0,      p.grid_j0};
  if (binned_for_ == key) return;
  const double cell = p.cell_size;
  const Vec3 origin(p.grid_origin.s[0], p.grid_origin.s[1], p.grid_origin.s[2]);
  // the columns a geometry can reach: its bounds grown by the farthest a particle's centre can be
  // from a surface it touches (the largest radius with its margin plus the speculative reach, the
  // kernel's widest static margin: narrowphase.cl static_reach), with the kernel's 1e-4 slack on
  // the squared distance and a thousandth of a cell for its float rounding of a particle's column;
  // clamped to the grid as the kernel clamps a particle's cell (a grid region's border columns
  // list what lies beyond them, as the whole grid's do). Planes reach everywhere. Until 2026-12-02
  // grown by a whole cell (which also holds the largest radius with its margin): the same
  // contacts in the same order, with a third more boxes listed in the type-G zone's columns
  const double static_reach =
      1.0001 * (max_radius_ * (1.0 + settings_.margin_rel) + p.speculative) + 1e-3 * cell;
  struct ColumnRange {
    int i0, i1, j0, j1;
  };
  const auto column = [&](double x, double x0, int first, int n) {
    const double c = std::floor((x - x0) / cell) - first;
    return static_cast<int>(std::clamp(c, 0.0, double(n - 1)));
  };
  std::vector<ColumnRange> ranges;
  ranges.reserve(geoms_.size());
  for (const StaticGeom& g : geoms_) {
    if (g.type == StaticGeom::Type::Plane) {
      ranges.push_back({0, nx - 1, 0, ny - 1});
      continue;
    }
    const Vec3 reach = g.axes.cwiseAbs() * g.half + Vec3::Constant(static_reach);
    ranges.push_back({column(g.centre.x() - reach.x(), origin.x(), p.grid_i0, nx),
                      column(g.centre.x() + reach.x(), origin.x(), p.grid_i0, nx),
                      column(g.centre.y() - reach.y(), origin.y(), p.grid_j0, ny),
                      column(g.centre.y() + reach.y(), origin.y(), p.grid_j0, ny)});
  }
  // count per column, prefix sum, then fill in geometry order (each list ascending)
  std::vector<int> start(static_cast<size_t>(nx) * ny + 1, 0);
  for (const ColumnRange& r : ranges)
    for (int j = r.j0; j <= r.j1; ++j)
      for (int i = r.i0; i <= r.i1; ++i) ++start[static_cast<size_t>(j) * nx + i + 1];
  for (size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  std::vector<int> list(std::max(start.back(), 1));
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (size_t g = 0; g < ranges.size(); ++g) {
    const ColumnRange& r = ranges[g];
    for (int j = r.j0; j <= r.j1; ++j)
      for (int i = r.i0; i <= r.i1; ++i)
        list[fill[static_cast<size_t>(j) * nx + i]++] = static_cast<int>(g);
  }
  buffers_.geom_column_start.upload(start);
  buffers_.geom_column_list.upload(list);
  // (recorded once the lists are on the device: a binning that threw is made again)
  binned_for_ = key;
}

void DemWorld::set_particles(const Particles& in) {
  size_t n = in.size();
  std::vector<cl_float4> x(n), v(n), w(n), q(n);
  max_radius_ = 0.0;
  for (size_t i = 0; i < n; ++i) {
    x[i] = to_float4(in.position[i], in.radius[i]);
    v[i] = to_float4(in.velocity[i], in.inv_mass[i]);
    w[i] = to_float4(in.omega[i], in.inv_inertia[i]);
    const auto& r = in.rotation[i];
    q[i] = to_float4(r.head<3>(), r.w());
    max_radius_ = std::max(max_radius_, in.radius[i]);
  }
  particle_count_ = n;
  buffers_.position.upload(x);
  buffers_.velocity.upload(v);
  buffers_.omega.upload(w);
  buffers_.rotation.upload(q);
  buffers_.has_previous = false;
  buffers_.n_contacts = 0;
  colours_carried_ = false;
  sweep_.reset();
  update_params();
}

void DemWorld::resize_particles(const Particles& in) {
  const size_t n = in.size();
  if (n != particle_count_)
    throw Error("DemWorld::resize_particles: " + std::to_string(n) + " particles for the " +
                std::to_string(particle_count_) + " the world holds");
  // the three arrays whose w lanes hold a size: position (radius), velocity (inverse mass) and
  // omega (inverse inertia), written whole as set_particles writes them
  std::vector<cl_float4> x(n), v(n), w(n);
  max_radius_ = 0.0;
  for (size_t i = 0; i < n; ++i) {
    x[i] = to_float4(in.position[i], in.radius[i]);
    v[i] = to_float4(in.velocity[i], in.inv_mass[i]);
    w[i] = to_float4(in.omega[i], in.inv_inertia[i]);
    max_radius_ = std::max(max_radius_, in.radius[i]);
  }
  buffers_.position.upload(x);
  buffers_.velocity.upload(v);
  buffers_.omega.upload(w);
  update_params();
}

void DemWorld::renumber_particles(const Particles& in, const std::vector<int>& new_index_of_old) {
  DemBuffers& b = buffers_;
  const size_t old_count = particle_count_;
  // survivors numbered 0, 1, 2, ... in their old order (so each contact's owner stays its lower
  // index and the lists stay grouped as the narrow phase groups them), within the new particles
  int next = 0;
  for (int k : new_index_of_old) {
    if (k < 0) continue;
    if (k != next)
      throw Error(
          "DemWorld::renumber_particles: the surviving particles must keep their order and "
          "come first (old particle renumbered " +
          std::to_string(k) + ", expected " + std::to_string(next) + ")");
    ++next;
  }
  if (new_index_of_old.size() != old_count || static_cast<size_t>(next) > in.size())
    throw Error("DemWorld::renumber_particles: the numbering covers " +
                std::to_string(new_index_of_old.size()) + " particles with " +
                std::to_string(next) + " survivors, the world holds " + std::to_string(old_count) +
                " and is given " + std::to_string(in.size()));
  // last step's contacts, their owners' offsets and their colours, read before the replacement
  const bool had_previous = b.has_previous && old_count > 0;
  const bool carried = colours_carried_;
  const int fresh = fresh_colours_;
  const int prev = 1 - b.current;
  std::vector<int> offsets;
  std::vector<TlContact> contacts;
  std::vector<int> colours;
  if (had_previous) {
    // read behind one wait
    PendingReads reads(dev_);
    b.owner_offsets[prev].enqueue_download(offsets, old_count + 1);
    if (b.n_contacts > 0) b.contacts[prev].enqueue_download(contacts, b.n_contacts);
    if (carried && b.n_contacts > 0) b.colour_previous.enqueue_download(colours, b.n_contacts);
    reads.wait();
  }
  set_particles(in);
  if (!had_previous) return;
  // the contacts between survivors, renumbered, in the same order; new particles own none
  std::vector<int> kept_offsets(in.size() + 1, 0);
  std::vector<TlContact> kept;
  std::vector<int> kept_colours;
  for (size_t a = 0; a < old_count; ++a) {
    const int owner = new_index_of_old[a];
    if (owner < 0) continue;
    for (int k = offsets[a]; k < offsets[a + 1]; ++k) {
      TlContact c = contacts[k];
      if (c.b >= 0 && new_index_of_old[c.b] < 0) continue;
      if (c.b >= 0) c.b = new_index_of_old[c.b];
      c.a = owner;
      kept.push_back(c);
      if (carried) kept_colours.push_back(colours[k]);
    }
    kept_offsets[owner + 1] = static_cast<int>(kept.size());
  }
  for (size_t i = static_cast<size_t>(next) + 1; i < kept_offsets.size(); ++i)
    kept_offsets[i] = static_cast<int>(kept.size());
  b.owner_offsets[prev].upload(kept_offsets);
  if (!kept.empty()) b.contacts[prev].upload(kept);
  if (carried && !kept_colours.empty()) b.colour_previous.upload(kept_colours);
  b.n_contacts = static_cast<int>(kept.size());
  b.has_previous = true;
  colours_carried_ = carried;
  fresh_colours_ = fresh;
  // the partition of last step's rows belongs to the old numbering: the next step makes its own
  colouring_made_ = false;
}

Particles DemWorld::particles() const {
  Particles out;
  // the four arrays read behind one wait
  std::vector<cl_float4> x, v, w, q;
  PendingReads reads(dev_);
  buffers_.position.enqueue_download(x, particle_count_);
  buffers_.velocity.enqueue_download(v, particle_count_);
  buffers_.omega.enqueue_download(w, particle_count_);
  buffers_.rotation.enqueue_download(q, particle_count_);
  reads.wait();
  for (size_t i = 0; i < particle_count_; ++i) {
    out.position.emplace_back(x[i].s[0], x[i].s[1], x[i].s[2]);
    out.radius.push_back(x[i].s[3]);
    out.velocity.emplace_back(v[i].s[0], v[i].s[1], v[i].s[2]);
    out.inv_mass.push_back(v[i].s[3]);
    out.omega.emplace_back(w[i].s[0], w[i].s[1], w[i].s[2]);
    out.inv_inertia.push_back(w[i].s[3]);
    out.rotation.emplace_back(q[i].s[0], q[i].s[1], q[i].s[2], q[i].s[3]);
  }
  return out;
}

void DemWorld::save_state(ByteWriter& w) const {
  const DemBuffers& b = buffers_;
  w.u64(particle_count_);
  w.f64(max_radius_);
  w.f64(time_);
  // the particles in the device layout (kernels/dem_types.h), no double round trip
  const size_t n = particle_count_;
  write_words(w, n > 0 ? b.position.download(n) : std::vector<cl_float4>());
  write_words(w, n > 0 ? b.velocity.download(n) : std::vector<cl_float4>());
  write_words(w, n > 0 ? b.omega.download(n) : std::vector<cl_float4>());
  write_words(w, n > 0 ? b.rotation.download(n) : std::vector<cl_float4>());
  // last step's contacts and their owners' offsets: end_step flipped `current`, so they are the
  // other pair, which the next narrow phase matches new contacts against
  w.u8(b.has_previous ? 1 : 0);
  if (!b.has_previous) return;
  const int prev = 1 - b.current;
  write_words(w, b.owner_offsets[prev].download(n + 1));
  write_words(
      w, b.n_contacts > 0 ? b.contacts[prev].download(b.n_contacts) : std::vector<TlContact>());
  // their colours, which the next colouring carries (without them a restored run would colour
  // afresh and part from the saved one)
  w.u8(colours_carried_ ? 1 : 0);
  w.u32(static_cast<std::uint32_t>(fresh_colours_));
  if (colours_carried_)
    write_words(w,
                b.n_contacts > 0 ? b.colour_previous.download(b.n_contacts) : std::vector<int>());
}

void DemWorld::restore_state(ByteReader& r, bool any_count) {
  DemBuffers& b = buffers_;
  const std::uint64_t n = r.u64("particle count");
  // each particle is four float4 words at least: a count the file cannot hold is corrupt
  r.need_elements(n, 4 * sizeof(cl_float4), "particle count");
  if (!any_count && n != particle_count_)
    throw InputError(
        r.where() + ": the saved state has " + std::to_string(n) + " particles, this simulation " +
        std::to_string(particle_count_) +
        "; restore a state into a simulation made with the same scenario, level and seed");
  const double max_radius = r.f64("particles");
  const double time = r.f64("particle clock");
  const auto x = read_words<cl_float4>(r, "particle positions");
  const auto v = read_words<cl_float4>(r, "particle velocities");
  const auto w = read_words<cl_float4>(r, "particle angular velocities");
  const auto q = read_words<cl_float4>(r, "particle rotations");
  if (x.size() != n || v.size() != n || w.size() != n || q.size() != n)
    throw InputError(r.where() + ": the saved particle arrays differ in length (corrupt)");
  const bool has_previous = r.u8("particle contacts") != 0;
  std::vector<int> offsets;
  std::vector<TlContact> contacts;
  bool carried = false;
  int fresh_colours = 0;
  std::vector<int> colours;
  if (has_previous) {
    offsets = read_words<int>(r, "particle contact offsets");
    contacts = read_words<TlContact>(r, "particle contacts");
    // the offsets index the contacts on the device unchecked: start at 0, never decrease, end
    // at the count
    bool ordered = offsets.size() == n + 1 && offsets.front() == 0 &&
                   offsets.back() == static_cast<int>(contacts.size());
    for (size_t i = 0; ordered && i < n; ++i) ordered = offsets[i] <= offsets[i + 1];
    if (!ordered)
      throw InputError(r.where() + ": the saved contacts do not match their offsets (corrupt)");
    // one colour per contact, each a colour the kernels can index
    carried = r.u8("particle contact colours") != 0;
    const std::uint32_t fresh_count = r.u32("particle contact colours");
    if (fresh_count > TL_MAX_COLOURS)
      throw InputError(r.where() + ": the saved colour count " + std::to_string(fresh_count) +
                       " is more than the colouring can make (corrupt)");
    fresh_colours = static_cast<int>(fresh_count);
    if (carried) {
      colours = read_words<int>(r, "particle contact colours");
      bool fits = colours.size() == contacts.size();
      for (size_t c = 0; fits && c < colours.size(); ++c)
        fits = colours[c] >= 0 && colours[c] < TL_MAX_COLOURS;
      if (!fits)
        throw InputError(r.where() +
                         ": the saved contact colours do not fit the contacts (corrupt)");
    }
  }
  // the largest radius sizes the broad phase's cells: finite, and at least every particle's
  float largest = 0.0f;
  for (const cl_float4& p : x) largest = std::max(largest, p.s[3]);
  if (!(std::isfinite(max_radius) && max_radius >= largest && (n == 0 || max_radius > 0.0)))
    throw InputError(r.where() + ": the saved largest radius " + std::to_string(max_radius) +
                     " m does not fit the particles (corrupt)");
  // everything read: the world is changed only now, so a bad file leaves it as it was
  if (n > 0) {
    b.position.upload(x);
    b.velocity.upload(v);
    b.omega.upload(w);
    b.rotation.upload(q);
  }
  particle_count_ = n;
  max_radius_ = max_radius;
  time_ = time;
  b.current = 0;
  b.has_previous = has_previous;
  b.static_previous = has_previous;
  // the saved contacts come with their colours but not their partition: the next step makes it,
  // carrying the colours as the saved run would have
  colouring_made_ = false;
  colours_made_ = false;
  colours_carried_ = carried;
  fresh_colours_ = fresh_colours;
  if (carried && !colours.empty()) b.colour_previous.upload(colours);
  b.n_contacts = static_cast<int>(contacts.size());
  if (has_previous) {
    b.owner_offsets[1].upload(offsets);
    if (!contacts.empty()) b.contacts[1].upload(contacts);
  }
  sweep_.reset();
  update_params();
}

void DemWorld::check_finite() {
  DemBuffers& b = buffers_;
  const int n = static_cast<int>(particle_count_);
  // the lowest bad index, by an atomic minimum (the same answer whatever the work-item order)
  b.first_non_finite.fill(std::numeric_limits<int>::max());
  set_args(k_first_non_finite_, b.position, b.velocity, b.omega, n, b.first_non_finite);
  launch(dev_, k_first_non_finite_, particle_count_, "first_non_finite");
  const int bad = b.first_non_finite.read_one(0);
  if (bad == std::numeric_limits<int>::max()) return;
  // what the particle holds, for the message
  const cl_float4 x = b.position.read_one(bad), v = b.velocity.read_one(bad),
                  w = b.omega.read_one(bad);
  std::ostringstream m;
  m << "particle state became non-finite at t = " << time_ << " s (step "
    << std::lround(time_ / settings_.dt) << "): particle " << bad << " of " << n
    << " has position (" << x.s[0] << ", " << x.s[1] << ", " << x.s[2] << "), radius " << x.s[3]
    << ", velocity (" << v.s[0] << ", " << v.s[1] << ", " << v.s[2] << "), angular velocity ("
    << w.s[0] << ", " << w.s[1] << ", " << w.s[2]
    << "). Likely causes: a non-finite number in the input (a file's field or a flag), or a "
    << "blow-up (a timestep too long for the contact stiffness, or a body pushed far faster than "
    << "DemSettings::max_speed); the run stops here rather than go on with garbage";
  throw Error(m.str());
}

void DemWorld::broad_phase() {
  DemBuffers& b = buffers_;
  const TlStepParams& p = params_;
  size_t n = particle_count_;
  size_t cells = size_t(p.grid_nx) * p.grid_ny * p.grid_nz;
  // count particles per cell, prefix-sum into starts, place, then order each cell by index
  b.particle_cell.resize(n);
  b.cell_counts.resize(cells);
  b.cell_counts.fill(0);
  set_args(k_cell_count_, b.position, b.particle_cell, b.cell_counts, p);
  launch(dev_, k_cell_count_, n, "cell_count");
  scan_.exclusive(b.cell_counts, b.cell_start, cells);
  b.cell_fill.resize(cells);
  b.cell_fill.fill(0);
  b.cell_particles.resize(std::max<size_t>(n, 1));
  set_args(k_cell_fill_, b.particle_cell, b.cell_start, b.cell_fill, b.cell_particles, p);
  launch(dev_, k_cell_fill_, n, "cell_fill");
  set_args(k_cell_sort_, b.cell_start, b.cell_particles, static_cast<int>(cells));
  launch(dev_, k_cell_sort_, cells, "cell_sort");
}

void DemWorld::narrow_phase() {
  // the static geometry's column lists for this grid and geometry (made here, where they are
  // read, so a step whose grid region and geometry both change bins once)
  bin_geoms();
  DemBuffers& b = buffers_;
  const TlStepParams& p = params_;
  size_t n = particle_count_;
  int cur = b.current;
  int prev = 1 - cur;
  // count, offsets (with the total at [n]), then write with last step's impulses matched
  b.contact_counts.resize(std::max<size_t>(n, 1));
  if (!b.has_previous) {
    b.owner_offsets[prev].resize(n + 1);
    b.owner_offsets[prev].fill(0);
  }
  const int slots = settings_.narrow_phase_slots;
  b.contact_partners.resize(std::max<size_t>(n * static_cast<size_t>(slots), 1));
  set_args(k_contact_count_, b.position, b.velocity, b.cell_start, b.cell_particles, b.geoms,
           b.geom_column_start, b.geom_column_list, b.contact_counts, b.contacts[cur],
           b.owner_offsets[prev], b.contacts[prev], p, b.contact_partners, slots);
  launch(dev_, k_contact_count_, n, "contact_count");
  scan_.exclusive(b.contact_counts, b.owner_offsets[cur], n);
  b.n_contacts = b.owner_offsets[cur].read_one(n);
  b.contacts[cur].resize(std::max(b.n_contacts, 1));
  set_args(k_contact_write_, b.position, b.velocity, b.cell_start, b.cell_particles, b.geoms,
           b.geom_column_start, b.geom_column_list, b.owner_offsets[cur], b.contacts[cur],
           b.owner_offsets[prev], b.contacts[prev], p,
           b.has_previous ? TL_MATCH_PAIRS | (b.static_previous ? TL_MATCH_STATIC : 0) : 0,
           b.contact_partners, slots);
  launch(dev_, k_contact_write_, n, "contact_write");
}

bool DemWorld::one_item_sweeps() const { return sweep_ && sweep_->walks_in_one_item(0); }

bool DemWorld::rows_interleaved(int rows) const {
  return settings_.sweep == SweepKind::Pgs && settings_.serial_lanes > 0 && sweep_ &&
         sweep_->walks_in_one_item(rows);
}

bool DemWorld::rows_in_runs(int rows) const {
  return settings_.sweep == SweepKind::Pgs && settings_.serial_lanes > 0 && sweep_ &&
         sweep_->walks_in_runs(rows);
}

int DemWorld::sweep_parts() const {
  if (settings_.sweep_parts > 0) return settings_.sweep_parts;
  return std::clamp(dev_.compute_units(), 1, kMaxSweepParts);
}

bool DemWorld::colouring_still_holds() {
  DemBuffers& b = buffers_;
  // made for the last step's contacts, as many as now, of as many particles, for this sweep
  if (!colouring_made_ || !b.has_previous || coloured_contacts_ != b.n_contacts ||
      coloured_particles_ != particle_count_ || coloured_sweep_ != settings_.sweep ||
      coloured_lanes_ != settings_.serial_lanes ||
      coloured_one_group_rows_ != settings_.one_group_rows || coloured_parts_ != sweep_parts())
    return false;
  if (b.n_contacts == 0) return true;
  // the same pairs, index for index (one integer read back: a host wait, as the narrow phase's)
  b.pairs_differ.fill(0);
  set_args(k_pairs_differ_, b.contacts[b.current], b.contacts[1 - b.current], b.n_contacts,
           b.pairs_differ);
  launch(dev_, k_pairs_differ_, b.n_contacts, "contact_pairs_differ");
  return b.pairs_differ.read_one(0) == 0;
}

void DemWorld::build_adjacency() {
  DemBuffers& b = buffers_;
  size_t n = particle_count_;
  int nc = b.n_contacts;
  const Buffer<TlContact>& contacts = b.contacts[b.current];
  b.degree.resize(std::max<size_t>(n, 1));
  b.degree.fill(0);
  set_args(k_adj_count_, contacts, nc, b.degree);
  launch(dev_, k_adj_count_, nc, "adjacency_count");
  scan_.exclusive(b.degree, b.adjacency_offsets, n);
  b.adjacency_fill.resize(std::max<size_t>(n, 1));
  b.adjacency_fill.fill(0);
  b.adjacency.resize(std::max(2 * nc, 1));
  set_args(k_adj_fill_, contacts, nc, b.adjacency_offsets, b.adjacency_fill, b.adjacency);
  launch(dev_, k_adj_fill_, nc, "adjacency_fill");
  set_args(k_adj_sort_, b.adjacency_offsets, b.adjacency, static_cast<int>(n));
  launch(dev_, k_adj_sort_, n, "adjacency_sort");
}

void DemWorld::colour_contacts() {
  DemBuffers& b = buffers_;
  int nc = b.n_contacts;
  b.order.resize(std::max(nc, 1));
  b.row_of_contact.resize(std::max(nc, 1));
  b.row_layout = RowLayout::Colours;
  if (settings_.sweep == SweepKind::Jacobi) {
    set_args(k_identity_, nc, b.order, b.row_of_contact);
    launch(dev_, k_identity_, nc, "identity_order");
    b.colour_start = {0, nc};
    b.colour_rounds = 0;
    colours_made_ = false;
    return;
  }
  if (rows_interleaved(nc)) {
    // one work-item walks the rows in turn: no colours, rows interleaved from blocks of contacts
    // (the sweeps read the one range from the device)
    set_args(k_interleaved_, nc, settings_.serial_lanes, b.order, b.row_of_contact);
    launch(dev_, k_interleaved_, nc, "interleaved_order");
    b.colour_start = {0, nc};
    b.colour_start_dev.upload(b.colour_start);
    b.colour_rounds = 0;
    b.row_layout = RowLayout::Interleaved;
    colours_made_ = false;
    return;
  }
  if (rows_in_runs(nc)) {
    // a work-item per run walks its rows, level by level: each contact's run, the contacts run
    // by run (the colours' stable partition), each run interleaved
    const int parts = sweep_parts();
    const int runs = tl_runs(parts);
    if (runs > TL_MAX_COLOURS)
      throw Error("DemWorld: " + std::to_string(parts) + " parts make " + std::to_string(runs) +
                  " runs, more than the partition's " + std::to_string(TL_MAX_COLOURS) +
                  " (internal error: kMaxSweepParts is too large)");
    b.part.resize(std::max(nc, 1));
    b.by_part.resize(std::max(nc, 1));
    set_args(k_contact_part_, b.contacts[b.current], nc, static_cast<int>(particle_count_), parts,
             b.part);
    launch(dev_, k_contact_part_, nc, "contact_part");
    partition_rows(b.part, b.by_part);
    set_args(k_interleave_runs_, b.by_part, b.colour_start_dev, runs, nc, settings_.serial_lanes,
             b.order, b.row_of_contact);
    launch(dev_, k_interleave_runs_, nc, "interleave_runs");
    // every run kept, empty or not: the sweep launches each level's runs together
    b.colour_start = b.colour_start_dev.download(runs + 1);
    b.run_parts = parts;
    b.colour_rounds = 0;
    b.row_layout = RowLayout::Runs;
    colours_made_ = false;
    return;
  }
  colours_made_ = false;  // until the colouring below is whole (it may throw)
  const Buffer<TlContact>& contacts = b.contacts[b.current];
  b.colour.resize(std::max(nc, 1));
  b.colour_next.resize(std::max(nc, 1));
  const bool carry = colours_carried_ && b.has_previous;
  if (carry) {
    // last step's colours for the contacts that persist, then the guard against a shared one
    set_args(k_carry_colours_, contacts, nc, b.colour_previous, b.colour_next);
    launch(dev_, k_carry_colours_, nc, "carry_colours");
    set_args(k_drop_conflicts_, contacts, nc, b.adjacency_offsets, b.adjacency, b.colour_next,
             fresh_colours_, b.colour);
    launch(dev_, k_drop_conflicts_, nc, "drop_colour_conflicts");
  } else {
    b.colour.fill(-1);
  }
  // jones-plassmann rounds until every contact has a colour
  int round = 0;
  for (int remaining = nc; remaining > 0;) {
    // a batch of rounds, each counting into its own status words, then one look at them all (one
    // host wait per batch, not per round): a round after the last contact got its colour copies
    // the colours unchanged, so the batch's spare rounds change nothing
    b.colour_status.resize(2 * kColourRoundsPerCheck);
    b.colour_status.fill(0);
    for (int r = 0; r < kColourRoundsPerCheck; ++r) {
      // this round reads the earlier rounds' colours and writes all colours into the other buffer
      set_args(k_colour_round_, contacts, nc, b.adjacency_offsets, b.adjacency, b.colour,
               b.colour_next, b.colour_status, r);
      launch(dev_, k_colour_round_, nc, "colour_round");
      std::swap(b.colour, b.colour_next);
    }
    const std::vector<int> status = b.colour_status.download(2 * kColourRoundsPerCheck);
    for (int r = 0; r < kColourRoundsPerCheck && remaining > 0; ++r, ++round) {
      if (status[2 * r + 1] > 0)
        throw Error("contact colouring needs more than " + std::to_string(TL_MAX_COLOURS) +
                    " colours: a particle touches too many others (particles far smaller than "
                    "their neighbours?); use the Jacobi sweep for such systems");
      if (status[2 * r] >= remaining)
        throw Error("contact colouring made no progress (internal error)");
      remaining = status[2 * r];
    }
  }
  b.colour_rounds = round;
  partition_rows(b.colour, b.order);
  // host copy of the ranges, trimmed to the colours in use
  b.colour_start = b.colour_start_dev.download(TL_MAX_COLOURS + 1);
  while (b.colour_start.size() > 2 && b.colour_start[b.colour_start.size() - 2] == nc)
    b.colour_start.pop_back();
  if (!carry) fresh_colours_ = static_cast<int>(b.colour_start.size()) - 1;
  colours_made_ = true;
}

void DemWorld::partition_rows(const Buffer<int>& colour, Buffer<int>& order) {
  DemBuffers& b = buffers_;
  const int nc = b.n_contacts;
  // stable partition by colour: block histograms, one scan, block scatters, each colour's start
  int blocks = std::max(1, (nc + kColourBlock - 1) / kColourBlock);
  b.colour_histogram.resize(size_t(TL_MAX_COLOURS) * blocks);
  set_args(k_colour_hist_, colour, nc, blocks, b.colour_histogram);
  launch(dev_, k_colour_hist_, blocks, "colour_histogram");
  scan_.exclusive(b.colour_histogram, b.colour_offsets, size_t(TL_MAX_COLOURS) * blocks);
  set_args(k_colour_scatter_, colour, nc, blocks, b.colour_offsets, order, b.row_of_contact);
  launch(dev_, k_colour_scatter_, blocks, "colour_scatter");
  set_args(k_colour_ranges_, b.colour_offsets, blocks, b.colour_start_dev);
  launch(dev_, k_colour_ranges_, TL_MAX_COLOURS + 1, "colour_ranges");
}

void DemWorld::prepare_rows() {
  DemBuffers& b = buffers_;
  int nc = b.n_contacts;
  b.rows.resize(std::max(nc, 1));
  b.impulses.resize(std::max(nc, 1));
  set_args(k_prepare_, b.contacts[b.current], b.order, nc, b.velocity, b.omega, b.rows, b.impulses,
           params_, settings_.warm_start ? 1 : 0);
  launch(dev_, k_prepare_, nc, "prepare_rows");
}

void DemWorld::apply_gravity() {
  set_args(k_gravity_, buffers_.velocity, params_);
  launch(dev_, k_gravity_, particle_count_, "apply_gravity");
}

void DemWorld::warm_start() {
  if (!settings_.warm_start) return;
  DemBuffers& b = buffers_;
  set_args(k_apply_impulses_, b.rows, b.impulses, b.adjacency_offsets, b.adjacency,
           b.row_of_contact, b.velocity, b.omega, params_);
  launch(dev_, k_apply_impulses_, particle_count_, "apply_row_impulses");
}

int DemWorld::sweep(int iterations) {
  // no contacts: nothing to sweep, and with a tolerance a residual of zero
  if (buffers_.n_contacts == 0) {
    if (settings_.tolerance > 0.0) stats_.residual = 0.0;
    return 0;
  }
  if (settings_.tolerance <= 0.0) {
    sweep_->iterate(buffers_, iterations);
    return iterations;
  }
  // with a tolerance: sweep up to each look of the schedule and stop once the residual is below
  // it (a last look at the cap, for the step's stats)
  ToleranceSchedule schedule(settings_.tolerance);
  int done = 0;
  while (done < iterations) {
    const int chunk = std::min(schedule.next_look(), iterations) - done;
    sweep_->iterate(buffers_, chunk);
    done += chunk;
    stats_.residual = residual();
    if (schedule.look(done, stats_.residual)) break;
  }
  return done;
}

void DemWorld::sweep_fixed(int iterations) {
  if (buffers_.n_contacts > 0) sweep_->iterate(buffers_, iterations);
}

void DemWorld::sweep_fixed_with_tools(int iterations, KinematicToolRows& tools) {
  sweep_->iterate_with_tools(buffers_, iterations, tools);
}

void DemWorld::store_impulses() {
  DemBuffers& b = buffers_;
  set_args(k_store_, b.rows, b.impulses, b.n_contacts, b.contacts[b.current]);
  launch(dev_, k_store_, b.n_contacts, "store_impulses");
}

void DemWorld::integrate() {
  DemBuffers& b = buffers_;
  set_args(k_integrate_, b.position, b.velocity, b.omega, b.rotation, params_);
  launch(dev_, k_integrate_, particle_count_, "integrate");
}

double DemWorld::residual() {
  DemBuffers& b = buffers_;
  int nc = b.n_contacts;
  if (nc == 0) return 0.0;
  // each row's squared residual, summed with the rows that act in blocks on the device, the
  // blocks' sums here
  const int blocks = (nc + kResidualBlock - 1) / kResidualBlock;
  b.residual.resize(nc);
  b.residual_block_sums.resize(blocks);
  set_args(k_residual_, b.rows, b.impulses, nc, b.velocity, b.omega, params_.relaxation,
           b.residual);
  launch(dev_, k_residual_, nc, "row_residual");
  set_args(k_sum_blocks_, b.residual, nc, kResidualBlock, b.residual_block_sums);
  launch(dev_, k_sum_blocks_, blocks, "sum_residual_blocks");
  auto sums = b.residual_block_sums.download(blocks);
  double sum = 0.0, acting = 0.0;
  for (const cl_float2& x : sums) {
    sum += x.s[0];
    acting += x.s[1];
  }
  // the RMS over the rows that act (kernels/solver.cl sum_residual_blocks); none: converged
  return acting > 0.0 ? std::sqrt(sum / acting) : 0.0;
}

void DemWorld::step() { step_impl(nullptr); }

std::vector<double> DemWorld::step_recording_residuals() {
  std::vector<double> history;
  step_impl(&history);
  return history;
}

void DemWorld::begin_step() {
  // settings changed through settings() take effect here (the params are a few numbers)
  update_params();
  stats_ = StepStats{};
  if (particle_count_ == 0) return;
  // contacts, colours and rows of this step (each a stage of a profiled run), from a state
  // checked finite
  {
    StageScope stage(dev_, "finite_check");
    check_finite();
  }
  {
    StageScope stage(dev_, "broad_phase");
    broad_phase();
  }
  {
    StageScope stage(dev_, "narrow_phase");
    narrow_phase();
  }
  {
    // a bed at rest pairs the same bodies step after step: their colouring is then kept, which
    // gives the bits a fresh one would (it depends on the pairs alone)
    StageScope stage(dev_, "colouring");
    stats_.colouring_kept = colouring_still_holds();
    if (!stats_.colouring_kept) {
      // not kept from here on until made whole (a colouring that throws leaves none)
      colouring_made_ = false;
      build_adjacency();
      colour_contacts();
      colouring_made_ = true;
      coloured_contacts_ = buffers_.n_contacts;
      coloured_particles_ = particle_count_;
      coloured_sweep_ = settings_.sweep;
      coloured_lanes_ = settings_.serial_lanes;
      coloured_one_group_rows_ = settings_.one_group_rows;
      coloured_parts_ = sweep_parts();
    }
  }
  {
    StageScope stage(dev_, "row_preparation");
    prepare_rows();
  }
  stats_.contacts = buffers_.n_contacts;
  stats_.colours = static_cast<int>(buffers_.colour_start.size()) - 1;
  const std::vector<int>& start = buffers_.colour_start;
  stats_.boundary_rows =
      buffers_.row_layout == RowLayout::Runs ? start.back() - start[buffers_.run_parts] : 0;
  stats_.colour_rounds = stats_.colouring_kept ? 0 : buffers_.colour_rounds;
}

void DemWorld::end_step() {
  if (particle_count_ > 0) {
    // keep the impulses for the next warm start, move the particles
    StageScope stage(dev_, "integration");
    store_impulses();
    integrate();
    // this step's colours are what the next step's colouring carries, unless they have grown
    colours_carried_ =
        colours_made_ &&
        carry_colours_after(static_cast<int>(buffers_.colour_start.size()) - 1, fresh_colours_);
    if (colours_made_) buffers_.colour_previous.copy_from(buffers_.colour);
    buffers_.has_previous = true;
    buffers_.static_previous = true;
    buffers_.current = 1 - buffers_.current;
  }
  time_ += settings_.dt;
}

void DemWorld::step_impl(std::vector<double>* history) {
  begin_step();
  if (particle_count_ > 0) {
    // velocities: external forces, warm start, then the sweeps
    apply_gravity();
    warm_start();
    if (history == nullptr) {
      // the sweeps are timed on their own for throughput (contact updates per second)
      dev_.finish();
      auto t0 = std::chrono::steady_clock::now();
      stats_.iterations = sweep(settings_.iterations);
      dev_.finish();
      stats_.sweep_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    } else {
      history->push_back(residual());
      for (int it = 0; it < settings_.iterations; ++it) {
        sweep(1);
        history->push_back(residual());
      }
      stats_.iterations = settings_.iterations;
    }
    // with a tolerance sweep() left its last look's residual in the stats
    if (history != nullptr) stats_.residual = history->back();
  }
  end_step();
}

}  // namespace talus
