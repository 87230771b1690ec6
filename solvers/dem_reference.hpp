// A double-precision CPU twin of every DEM device stage (kernels/*.cl), written for reading
// rather than speed. Each function mirrors one kernel's math step by step, in double, so that
// tests can run a stage on the device and here on the same inputs and compare the results:
// discrete results (scan, cells, contact pairs, adjacency, colours) must match exactly,
// real-valued ones within float rounding.
//
// The reference keeps the device's conventions: contacts grouped by owner particle a in the
// narrow phase's enumeration order, b < 0 naming static geometry -1-b, normals from a towards
// b, impulses acting on b (and the opposite on a).
#pragma once
#include <vector>

#include "kernels/common.h"
#include "kernels/dem_types.h"
#include "solvers/contact_rows.hpp"
#include "solvers/dem_settings.hpp"
#include "solvers/particles.hpp"

namespace talus::reference {

// the double layouts and conversions production shares with the reference (solvers/contact_rows)
using Row = ContactRow;
using talus::from_device;
using talus::hertz_stiffness;
using talus::particles_from_device;
using talus::StepParams;


// a contact as the narrow phase writes it (kernels/dem_types.h TlContact), in double
struct Contact {
  Vec3 normal = Vec3::Zero();     // unit normal from a towards b
  double gap = 0.0;               // [m], negative = overlap
  Vec3 arm_a = Vec3::Zero();      // lever arm from a's centre to the contact point
  Vec3 arm_b = Vec3::Zero();      // lever arm from b's centre (zero for static b)
  double reduced_radius = 0.0;    // R* [m]
  double stiffness = 0.0;         // hertz k_n [N/m^1.5]
  double impulse_n = 0.0;         // normal impulse on b [N s]
  Vec3 impulse_t = Vec3::Zero();  // friction impulse on b [N s]
  Vec3 impulse_r = Vec3::Zero();  // rolling + twisting impulse on b [N m s]
  int a = 0, b = 0;               // bodies; b < 0 is static geometry -1-b
  int previous = -1;              // the same (a, b) in last step's list; -1 new or none
};

// contacts grouped by owner: those of particle i are [owner_offsets[i], owner_offsets[i+1])
struct ContactSet {
  std::vector<Contact> contacts;
  std::vector<int> owner_offsets;  // particles + 1 entries
};

// the broad-phase grid: each particle's cell, and the particles of each cell in index order
struct CellLists {
  std::vector<int> particle_cell;   // per particle
  std::vector<int> cell_start;      // cells + 1 entries
  std::vector<int> cell_particles;  // particles, grouped by cell
};

// body -> contact adjacency (CSR); each body's list in contact order
struct Adjacency {
  std::vector<int> offsets;   // particles + 1 entries
  std::vector<int> contacts;  // contact indices
  int degree(int body) const { return offsets[body + 1] - offsets[body]; }
};

// contacts laid out as rows, colour after colour
struct Partition {
  std::vector<int> order;           // row -> contact
  std::vector<int> row_of_contact;  // contact -> row
  std::vector<int> colour_start;    // rows of colour k are [colour_start[k], colour_start[k+1])
};


// conversions from the device layouts (float to double is exact); those of the step parameters,
// rows and particles are production's (solvers/contact_rows.hpp)
StaticGeom from_device(const TlGeom& g);
Contact from_device(const TlContact& c);

// kernels/scan.cl: exclusive prefix sum with the total appended (n + 1 entries)
std::vector<int> exclusive_scan(const std::vector<int>& values);

// kernels/dem_common.cl cell_of / cell_index: the clamped grid cell of a point
int cell_of(const Vec3& x, const StepParams& p);

// kernels/broadphase.cl: counting sort of particles into grid cells
CellLists cell_lists(const Particles& particles, const StepParams& p);

// kernels/dem_common.cl sphere_geom: unit normal from the sphere into g, and the gap
double sphere_geom(const Vec3& x, double r, const StaticGeom& g, Vec3* normal);

// kernels/dem_common.cl contact_priority: the bijective 32-bit mix used by the colouring
unsigned contact_priority(unsigned c);

// kernels/narrowphase.cl: every pair closer than the margin, in the kernel's enumeration
// order, each with the index of the same pair in `previous` (when given), and last step's
// impulses carried over for those pairs (static contacts only with `match_static`:
// TL_MATCH_STATIC, off after the geometry was renumbered)
ContactSet find_contacts(const Particles& particles, const std::vector<StaticGeom>& geoms,
                         const CellLists& cells, const StepParams& p,
                         const ContactSet* previous = nullptr, bool match_static = true);

// kernels/narrowphase.cl adjacency_*: each body's contacts in contact order
Adjacency adjacency(const std::vector<Contact>& contacts, int particles);

// kernels/colouring.cl carry_colours + drop_colour_conflicts: each contact's colour of last
// step through its `previous` (-1 when new), dropped where it is `cap` or more or a neighbour of
// lower index carries the same one
std::vector<int> carried_colours(const std::vector<Contact>& contacts, const Adjacency& adjacency,
                                 const std::vector<int>& previous_colours, int cap);

// kernels/colouring.cl colour_round: jones-plassmann rounds with the kernel's priorities over
// the contacts `start` leaves uncoloured (-1; an empty `start`: all of them); returns each
// contact's colour (0..TL_MAX_COLOURS-1) and the number of rounds.
// Throws talus::Error when a contact would need more than TL_MAX_COLOURS colours.
std::vector<int> colour_contacts(const std::vector<Contact>& contacts, const Adjacency& adjacency,
                                 int* rounds = nullptr, std::vector<int> start = {});

// kernels/colouring.cl histogram/scatter/ranges: stable partition of contacts by colour,
// colour_start trimmed to the colours in use as DemWorld::colour_contacts does
Partition partition_by_colour(const std::vector<int>& colours);

// kernels/colouring.cl identity_order: rows in contact order, one colour (Jacobi)
Partition identity_partition(int n_contacts);
// kernels/colouring.cl interleaved_order: the contacts in `lanes` blocks, the rows taking one of
// each block in turn, one colour (a sweep one work-item walks; DemSettings::serial_lanes)
Partition interleaved_partition(int n_contacts, int lanes);
// kernels/colouring.cl contact_part + the stable partition + interleave_runs: the contacts of
// each run of `parts` parts of the particle indices (kernels/dem_types.h tl_run_of), run after
// run, each interleaved from `lanes` blocks; colour_start holds all tl_runs(parts) runs, empty
// ones kept (DemSettings::sweep_parts)
Partition run_partition(const std::vector<Contact>& contacts, int particles, int parts, int lanes);

// kernels/solver.cl prepare_rows: rows in `order`, from the velocities before gravity
std::vector<Row> prepare_rows(const std::vector<Contact>& contacts, const std::vector<int>& order,
                              const Particles& bodies, const StepParams& p, bool warm_start);

// kernels/solver.cl apply_gravity
void apply_gravity(Particles& bodies, const StepParams& p);

// kernels/solver.cl apply_row_impulses: each body receives its rows' current impulses
void apply_row_impulses(const std::vector<Row>& rows, const Adjacency& adjacency,
                        const std::vector<int>& row_of_contact, Particles& bodies);

// kernels/solver.cl pgs_colour: rows [begin, end) solved one after another
void pgs_colour(std::vector<Row>& rows, int begin, int end, Particles& bodies);
// one PGS sweep: every colour in turn (solvers/pgs_sweep.cpp)
void pgs_sweep(std::vector<Row>& rows, const std::vector<int>& colour_start, Particles& bodies);

// kernels/solver.cl jacobi_rows + jacobi_bodies: one projected jacobi sweep with mass splitting
void jacobi_iteration(std::vector<Row>& rows, const Adjacency& adjacency,
                      const std::vector<int>& row_of_contact, Particles& bodies);

// kernels/solver.cl row_residual: squared natural-map residual of each row [m^2/s^2], of plain
// Gauss-Seidel's step for rows made with `relaxation` (StepParams::relaxation)
std::vector<double> row_residuals(const std::vector<Row>& rows, const Particles& bodies,
                                  double relaxation);
// DemWorld::residual: the RMS of the row residuals over the rows that act (a normal impulse or a
// residual) [m/s]
double residual(const std::vector<Row>& rows, const Particles& bodies, double relaxation);

// kernels/solver.cl store_impulses: the rows' impulses back into their contacts
void store_impulses(const std::vector<Row>& rows, std::vector<Contact>& contacts);

// kernels/solver.cl integrate: x += h v, q += h/2 (omega, 0) q renormalised (dynamic bodies)
void integrate(Particles& bodies, const StepParams& p);

// a full CPU system: what DemWorld holds, in double
struct ReferenceWorld {
  Particles particles;
  std::vector<StaticGeom> geoms;
  StepParams params;
  DemSettings settings;
  ContactSet previous;        // last step's contacts with their solved impulses
  bool has_previous = false;  // false on the first step (no warm start source)
  // last step's PGS colours, which this step's colouring carries (DemWorld's colour_previous)
  std::vector<int> previous_colours;
  bool colours_carried = false;
  int fresh_colours = 0;  // colours of the last colouring that carried none
  // whether the device's one-group PGS sweep is one work-item walking the rows (a CPU device;
  // DemWorld::one_item_sweeps): systems of at most settings.one_group_rows rows are then laid out
  // interleaved instead of coloured (DemSettings::serial_lanes)
  bool one_item_sweeps = false;
  // on such a device, the parts larger systems are walked in (DemWorld::sweep_parts, resolved:
  // at least 1)
  int sweep_parts = 1;

  // by-products of the last step, for inspection
  CellLists cells;
  ContactSet current;
  Adjacency adjacency;
  Partition partition;
  std::vector<Row> rows;
  int colour_rounds = 0;
  int iterations = 0;
};

// one time step, the stages of DemWorld::step in the same order
void step(ReferenceWorld& world);

}  // namespace talus::reference
