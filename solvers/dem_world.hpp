// The particle (type-D) simulator on an OpenCL device: one DemWorld owns a granular system
// and steps it with the pipeline of SPEC §1 (broad phase, narrow phase with persistent
// contacts, colouring, SPOOK rows, PGS or Jacobi sweeps, position update).
//
// The stages are public so tests can run them one at a time and compare each with its
// double-precision twin in solvers/dem_reference.hpp.
#pragma once
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "host/binary.hpp"
#include "host/device.hpp"
#include "host/scan.hpp"
#include "solvers/contact_rows.hpp"
#include "solvers/contact_sweep.hpp"
#include "solvers/dem_buffers.hpp"
#include "solvers/dem_settings.hpp"
#include "solvers/particles.hpp"

namespace talus {

struct StepStats {
  int contacts = 0;
  int colours = 0;         // colours, or runs (RowLayout::Runs: every level's)
  int boundary_rows = 0;   // rows in runs across parts, walked after the parts (else 0)
  int colour_rounds = 0;   // Jones-Plassmann rounds launched (whole batches: solvers/dem_world.cpp)
  // the contacts paired the same bodies as the last step's, so their colouring was kept
  bool colouring_kept = false;
  int iterations = 0;      // sweeps run (fewer than settings.iterations when tolerance stopped)
  double residual = -1.0;  // RMS row residual after the sweeps [m/s]; -1 when not computed
  double sweep_seconds = 0.0;  // wall time of the sweeps (queue drained before and after)
};

// how new static geometry relates to the old, for warm starting (contacts with static geometry
// are matched by its index): Moved (the same list, moved: every contact keeps its impulses),
// Renumbered (another list: particle pairs keep theirs, static contacts start from zero; the
// type-G terrain's column boxes, remade each step), Replaced (every contact starts from zero)
enum class GeomChange { Moved, Renumbered, Replaced };

class DemWorld {
 public:
  DemWorld(Device& dev, const Material& material, const DemSettings& settings, const Bounds& bounds,
           std::vector<StaticGeom> geoms);

  // replaces the particles (contacts start fresh: no warm start on the next step)
  void set_particles(const Particles& particles);
  // replaces the particles with some of them renumbered, the rest removed and new ones added:
  // new_index_of_old[k] is old particle k's index in `particles`, -1 if it is gone. The survivors
  // must keep their order and come first (new particles after them), as the type-G terrain's merge
  // and spawn leave them. Last step's contacts between survivors keep their impulses and colours
  // for the next step's warm start and colouring; Error if the numbering is not such a one
  void renumber_particles(const Particles& particles, const std::vector<int>& new_index_of_old);
  // the same particles in the same order with a new state (their sizes, radius, inverse mass and
  // inertia: the type-G terrain's growing seeds; their places and motion, and inverse masses of
  // zero: the type-G bucket's riding load): last step's contacts, impulses and colours stay as
  // they are. Error if the count differs
  void resize_particles(const Particles& particles);
  // the state between two steps, for a saved state (digging/saved_state): the particles as the
  // device holds them (float bit for bit), last step's contacts with their impulses (the next
  // warm start), the largest radius and the clock. restore_state reads it into a world made with
  // the same material, settings, bounds and geometry and as many particles (InputError naming
  // the reader's file otherwise; with `any_count` the saved particles replace however many the
  // world holds, as the type-G terrain's, whose particles come and go); the world then steps on
  // bit-identically to the saved one on the same device and work-group size
  void save_state(ByteWriter& w) const;
  void restore_state(ByteReader& r, bool any_count = false);
  // replaces the static geometry (walls removed or moved, the type-G terrain's boxes); `change`
  // says which contacts keep last step's impulses
  void set_geoms(std::vector<StaticGeom> geoms, GeomChange change = GeomChange::Replaced);
  // the broad-phase grid over the cells of the bounds' grid that hold `region` (grown by a cell
  // each way) instead of all of them: a small system in large bounds (the type-G zone's
  // particles in the pile's container) clears, scans and sorts its few cells, not the
  // container's (G50: 5 of 28 ms a step; bench/RESULTS.md 2026-12-01). A particle keeps its cell
  // of the bounds' lattice, so while every particle lies in the region the contacts are the same,
  // in the same order, bit for bit; one outside it is clamped into the border cells as one
  // outside the bounds always was (every pair still found, their order may differ). The caller
  // sets it before each step from where its particles are; nullopt: the whole bounds again
  void set_grid_region(const std::optional<Bounds>& region);
  const std::optional<Bounds>& grid_region() const { return grid_region_; }
  // replaces the contact material (e.g. friction switched on after a dense fill)
  void set_material(const Material& material);
  const Material& material() const { return material_; }
  // the particles as they are on the device now
  Particles particles() const;
  size_t size() const { return particle_count_; }
  double max_radius() const { return max_radius_; }

  // one full time step: begin_step(), gravity, warm start, sweeps, end_step()
  void step();
  // the halves of a step around the velocity solve, for a coupled step that adds rows of its
  // own between them (solvers/split_solver): begin_step finds this step's contacts and makes
  // their rows; end_step keeps the impulses for the next warm start, moves the particles and
  // advances the clock
  void begin_step();
  void end_step();
  double time() const { return time_; }
  const StepStats& stats() const { return stats_; }
  const DemSettings& settings() const { return settings_; }
  DemSettings& settings() { return settings_; }
  const TlStepParams& params() const { return params_; }
  // whether the next colouring carries last step's colours (DemBuffers::colour_previous)
  bool carries_colours() const { return colours_carried_; }
  int fresh_colours() const { return fresh_colours_; }
  // whether this world's PGS sweep is one work-item walking the rows of a system up to
  // one_group_rows (a CPU device): such systems are laid out interleaved, not coloured
  // (DemSettings::serial_lanes; reference::ReferenceWorld::one_item_sweeps mirrors it). Known once
  // a step has begun
  bool one_item_sweeps() const;
  const std::vector<StaticGeom>& geoms() const { return geoms_; }

  // the stages of step(), in order
  // Error naming the time, the step, the first particle and its state when a position, radius,
  // velocity or angular velocity is not finite (checked at the start of every step, before the
  // contact search)
  void check_finite();
  void broad_phase();
  void narrow_phase();
  // whether this step's `rows` are laid out interleaved for one work-item instead of coloured
  // (DemSettings::serial_lanes)
  bool rows_interleaved(int rows) const;
  // whether this step's `rows` are laid out in runs (the parts' and those across them), each
  // walked by one work-item, instead of coloured (DemSettings::sweep_parts)
  bool rows_in_runs(int rows) const;
  // the parts a large system's rows are cut into: DemSettings::sweep_parts, or for 0 the
  // device's compute units (at most kMaxSweepParts)
  int sweep_parts() const;
  // whether this step's contacts (narrow_phase) pair the same bodies, index for index, as the
  // contacts the buffers' adjacency and colouring were made for (with the same serial_lanes and
  // one_group_rows): then those are this step's too
  bool colouring_still_holds();
  void build_adjacency();
  // PGS: graph colouring, carrying last step's colours to the contacts that persist (the same
  // result however often it runs within a step), or for a system one work-item walks the
  // interleaved rows (rows_interleaved), or for a larger one on such a device its runs
  // (rows_in_runs); Jacobi: one colour in contact order
  void colour_contacts();
  // the stable partition of the contacts by `colour` (a colour or a part each): the contacts
  // colour by colour in contact order into `order`, row_of_contact, and each colour's first row
  // in colour_start_dev (TL_MAX_COLOURS + 1 entries)
  void partition_rows(const Buffer<int>& colour, Buffer<int>& order);
  void prepare_rows();
  void apply_gravity();
  void warm_start();       // applies the rows' initial impulses to the bodies
  int sweep(int iterations);
  // exactly `iterations` sweeps over the particle rows, whatever the tolerance says
  void sweep_fixed(int iterations);
  // exactly `iterations` sweeps, each over the particle rows and then the kinematic tools' rows
  // (solvers/kinematic_tool_rows; one launch for a small PGS system)
  void sweep_fixed_with_tools(int iterations, KinematicToolRows& tools);
  void store_impulses();
  void integrate();

  // RMS of the row residuals (kernels/solver.cl row_residual) over the rows that act (an impulse or
  // a residual; a speculative row whose pair stays apart has neither) [m/s]: summed in blocks of
  // kResidualBlock rows on the device (sum_residual_blocks), the blocks' sums on the host in double
  double residual();
  // one step that records the residual after every sweep (diagnostics, convergence tables)
  std::vector<double> step_recording_residuals();

  DemBuffers& buffers() { return buffers_; }
  const DemBuffers& buffers() const { return buffers_; }
  Device& device() { return dev_; }

 private:
  void update_params();
  // the static geometry binned by the grid's (x, y) columns (DemBuffers::geom_column_*), made
  // by the narrow phase when the grid or the geometry changed since the last binning
  void bin_geoms();
  // one step; records the residual after every sweep when `history` is given
  void step_impl(std::vector<double>* history);

  Device& dev_;
  Material material_;
  DemSettings settings_;
  Bounds bounds_;
  std::optional<Bounds> grid_region_;  // set_grid_region's; none: the whole bounds
  std::vector<StaticGeom> geoms_;
  // what the columns' lists were binned for: the geometry (set_geoms counts its versions) and the
  // grid's columns. The narrow phase bins before it reads them, only when these changed: a type-G
  // step, whose boxes and grid region change every step, bins once (issue 14)
  struct GeomBinning {
    std::uint64_t geoms_version = 0;
    float cell_size = 0.0f, origin_x = 0.0f, origin_y = 0.0f;
    int nx = 0, ny = 0, i0 = 0, j0 = 0;
    bool operator==(const GeomBinning& o) const {
      return geoms_version == o.geoms_version && cell_size == o.cell_size &&
             origin_x == o.origin_x && origin_y == o.origin_y && nx == o.nx && ny == o.ny &&
             i0 == o.i0 && j0 == o.j0;
    }
  };
  std::uint64_t geoms_version_ = 0;
  std::optional<GeomBinning> binned_for_;
  TlStepParams params_{};
  size_t particle_count_ = 0;
  double max_radius_ = 0.0;
  double time_ = 0.0;
  StepStats stats_;

  DemBuffers buffers_;
  DeviceScan scan_;
  std::unique_ptr<ContactSweep> sweep_;
  // what the buffers' adjacency and colouring were made for: the last step's contacts (false
  // before the first colouring and after a restored state, whose contacts came without them),
  // their count, the particle count, the sweep kind, serial_lanes, one_group_rows and the parts
  bool colouring_made_ = false;
  // `colour` holds this step's PGS colours (false after a Jacobi colouring, an interleaved layout
  // or runs), and
  // `colour_previous` last step's, which the next colouring carries (false until a PGS step has
  // ended, after new particles, and after a restored state that saved none)
  bool colours_made_ = false;
  bool colours_carried_ = false;
  // colours of the last colouring that carried none (carry_colours_after)
  int fresh_colours_ = 0;
  int coloured_contacts_ = 0;
  size_t coloured_particles_ = 0;
  SweepKind coloured_sweep_ = SweepKind::Pgs;
  int coloured_lanes_ = 0;
  int coloured_one_group_rows_ = 0;
  int coloured_parts_ = 0;
  // what sweep_ was made for (DemSettings::sweep, one_group_rows): a change makes a new one
  SweepKind sweep_kind_;
  int sweep_one_group_rows_;
  cl::Kernel k_cell_count_, k_cell_fill_, k_cell_sort_;
  cl::Kernel k_contact_count_, k_contact_write_;
  cl::Kernel k_adj_count_, k_adj_fill_, k_adj_sort_;
  cl::Kernel k_colour_round_, k_colour_hist_, k_colour_scatter_, k_colour_ranges_, k_identity_,
      k_interleaved_, k_pairs_differ_, k_carry_colours_, k_drop_conflicts_, k_contact_part_,
      k_interleave_runs_;
  cl::Kernel k_prepare_, k_gravity_, k_apply_impulses_, k_store_, k_integrate_, k_residual_,
      k_sum_blocks_;
  cl::Kernel k_first_non_finite_;
};

// the host description of static geometry in the device layout
TlGeom to_device(const StaticGeom& g);

}  // namespace talus
