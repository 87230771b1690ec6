#include "solvers/dem_reference.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "host/error.hpp"
#include "solvers/contact_law.hpp"
#include "solvers/tolerance_schedule.hpp"

namespace talus::reference {

namespace {

// the margin below which a pair becomes a (possibly speculative) contact, its reach the
// fastest particle's or the pair's own closing (kernels/narrowphase.cl contact_margin)
double contact_margin(double ra, double rb, double closing, const StepParams& p) {
  double reach = p.speculative;
  if (p.pair_reach)
    reach = std::min(reach, 2.0 * p.dt * std::max(0.0, closing + p.gravity.norm() * p.dt));
  return p.margin_rel * std::min(ra, rb) + reach;
}

// the contact index where the previous step stored the pair (a, b); -1 when it is new
int find_previous(int a, int b, const ContactSet& previous) {
  for (int k = previous.owner_offsets[a]; k < previous.owner_offsets[a + 1]; ++k)
    if (previous.contacts[k].b == b) return k;
  return -1;
}

// a fresh contact, with the index of the same pair last step and, where `match`, that pair's
// impulses
Contact make_contact(int a, int b, const Vec3& normal, double gap, const Vec3& arm_a,
                     const Vec3& arm_b, double reduced_radius, const StepParams& p,
                     const ContactSet* previous, bool match) {
  Contact c;
  c.normal = normal;
  c.gap = gap;
  c.arm_a = arm_a;
  c.arm_b = arm_b;
  c.reduced_radius = reduced_radius;
  c.stiffness = hertz_stiffness(reduced_radius, p);
  c.a = a;
  c.b = b;
  if (previous != nullptr) {
    int k = find_previous(a, b, *previous);
    c.previous = k;
    if (match && k >= 0) {
      const Contact& old = previous->contacts[k];
      c.impulse_n = old.impulse_n;
      c.impulse_t = old.impulse_t;
      c.impulse_r = old.impulse_r;
    }
  }
  return c;
}

// a body's velocities, or zeros for static geometry
struct BodyVelocity {
  Vec3 v = Vec3::Zero();
  Vec3 w = Vec3::Zero();
  double inv_mass = 0.0;
  double inv_inertia = 0.0;
};

BodyVelocity body_velocity(const Particles& bodies, int i) {
  BodyVelocity out;
  if (i < 0) return out;
  out.v = bodies.velocity[i];
  out.w = bodies.omega[i];
  out.inv_mass = bodies.inv_mass[i];
  out.inv_inertia = bodies.inv_inertia[i];
  return out;
}

// the inverse masses and effective masses one contact is solved with (kernels/solver.cl
// solve_contact): the bodies' own in PGS, split ones in jacobi
struct SolveMasses {
  double inv_ma, inv_ia, inv_mb, inv_ib;
  double inv_dn, inv_dt, inv_dr;
};

// one contact's rows in sequence (normal, friction, rolling) against local copies of the two
// bodies' velocities; updates the row's impulses and returns the impulse changes
void solve_contact(Row& row, Vec3& va, Vec3& wa, Vec3& vb, Vec3& wb, const SolveMasses& m,
                   Vec3* d_lin, Vec3* d_ang) {
  const Vec3& n = row.normal;
  double ln = row.impulse_n;

  // normal: SPOOK row with compliance, lambda_n >= -h F_c (0 without cohesion)
  double un = n.dot(vb - va);
  double ln_new = contact_law::normal_impulse(ln, row.rhs, un, row.sigma, m.inv_dn, -row.cohesion);
  double dln = ln_new - ln;
  va -= m.inv_ma * dln * n;
  vb += m.inv_mb * dln * n;
  ln = ln_new;

  // friction: tangential relative velocity at the contact point, impulse on the disc
  // mu (lambda_n + h F_c)
  Vec3 u = (vb + wb.cross(row.arm_b)) - (va + wa.cross(row.arm_a));
  Vec3 ut = u - u.dot(n) * n;
  Vec3 lt = row.impulse_t;
  Vec3 lt_new = contact_law::friction_impulse(lt, ut, m.inv_dt, row.friction * (ln + row.cohesion));
  Vec3 dlt = lt_new - lt;
  va -= m.inv_ma * dlt;
  wa -= m.inv_ia * row.arm_a.cross(dlt);
  vb += m.inv_mb * dlt;
  wb += m.inv_ib * row.arm_b.cross(dlt);

  // rolling (tangential, on the disc) and twisting (about n), both bounded by
  // mu_r R* (lambda_n + h F_c)
  Vec3 wrel = wb - wa;
  Vec3 lr = row.impulse_r;
  Vec3 lr_new = contact_law::rolling_impulse(lr, wrel, n, m.inv_dr, row.rolling_limit * (ln + row.cohesion));
  Vec3 dlr = lr_new - lr;
  wa -= m.inv_ia * dlr;
  wb += m.inv_ib * dlr;

  row.impulse_n = ln;
  row.impulse_t = lt_new;
  row.impulse_r = lr_new;
  *d_lin = dln * n + dlt;
  *d_ang = dlr;
}

}  // namespace

// ---- conversions from the device layouts ----

StaticGeom from_device(const TlGeom& g) {
  StaticGeom out;
  out.type = g.type == TL_GEOM_PLANE ? StaticGeom::Type::Plane : StaticGeom::Type::Box;
  out.centre = xyz(g.centre);
  out.axes.col(0) = xyz(g.axis_x);
  out.axes.col(1) = xyz(g.axis_y);
  out.axes.col(2) = xyz(g.axis_z);
  out.half = xyz(g.half_extent);
  return out;
}

Contact from_device(const TlContact& c) {
  Contact out;
  out.normal = xyz(c.normal);
  out.gap = c.normal.s[3];
  out.arm_a = xyz(c.arm_a);
  out.reduced_radius = c.arm_a.s[3];
  out.arm_b = xyz(c.arm_b);
  out.stiffness = c.arm_b.s[3];
  out.impulse_t = xyz(c.impulse_t);
  out.impulse_n = c.impulse_t.s[3];
  out.impulse_r = xyz(c.impulse_r);
  out.a = c.a;
  out.b = c.b;
  out.previous = c.previous;
  return out;
}

// ---- scan and broad phase ----

std::vector<int> exclusive_scan(const std::vector<int>& values) {
  std::vector<int> out(values.size() + 1);
  int sum = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    out[i] = sum;
    sum += values[i];
  }
  out[values.size()] = sum;
  return out;
}

int cell_of(const Vec3& x, const StepParams& p) {
  // floor of the position in cell units of the lattice, then the grid's own index clamped into it
  Vec3 rel = (x - p.grid_origin) / p.cell_size;
  int cx = std::clamp(static_cast<int>(std::floor(rel.x())) - p.grid_i0, 0, p.grid_nx - 1);
  int cy = std::clamp(static_cast<int>(std::floor(rel.y())) - p.grid_j0, 0, p.grid_ny - 1);
  int cz = std::clamp(static_cast<int>(std::floor(rel.z())) - p.grid_k0, 0, p.grid_nz - 1);
  return (cz * p.grid_ny + cy) * p.grid_nx + cx;
}

CellLists cell_lists(const Particles& particles, const StepParams& p) {
  CellLists out;
  int n = static_cast<int>(particles.size());
  // count particles per cell, then starts by prefix sum
  std::vector<int> counts(p.cells(), 0);
  for (int i = 0; i < n; ++i) {
    int cell = cell_of(particles.position[i], p);
    out.particle_cell.push_back(cell);
    counts[cell]++;
  }
  out.cell_start = exclusive_scan(counts);
  // place particles in index order (what the kernel's sort restores)
  std::vector<int> next(out.cell_start.begin(), out.cell_start.end() - 1);
  out.cell_particles.assign(n, 0);
  for (int i = 0; i < n; ++i) out.cell_particles[next[out.particle_cell[i]]++] = i;
  return out;
}

// ---- narrow phase ----

double sphere_geom(const Vec3& x, double r, const StaticGeom& g, Vec3* normal) {
  const Vec3& c = g.centre;
  Vec3 ax = g.axes.col(0), ay = g.axes.col(1), az = g.axes.col(2);
  if (g.type == StaticGeom::Type::Plane) {
    *normal = -ax;
    return (x - c).dot(ax) - r;
  }
  // box: closest point in the box frame
  Vec3 d = x - c;
  Vec3 p_box(d.dot(ax), d.dot(ay), d.dot(az));
  const Vec3& h = g.half;
  Vec3 q = p_box.cwiseMax(-h).cwiseMin(h);
  Vec3 diff = p_box - q;
  double dist2 = diff.dot(diff);
  if (dist2 > 0.0) {
    double dist = std::sqrt(dist2);
    Vec3 nl = -diff / dist;
    *normal = nl.x() * ax + nl.y() * ay + nl.z() * az;
    return dist - r;
  }
  // centre inside: leave through the nearest face (ties to the lower axis, as the kernel)
  Vec3 depth = h - p_box.cwiseAbs();
  int k = depth.x() <= depth.y() ? (depth.x() <= depth.z() ? 0 : 2)
                                 : (depth.y() <= depth.z() ? 1 : 2);
  double s = p_box[k] >= 0.0 ? 1.0 : -1.0;
  *normal = -s * g.axes.col(k);
  return -depth[k] - r;
}

unsigned contact_priority(unsigned c) {
  uint32_t x = c;
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

ContactSet find_contacts(const Particles& particles, const std::vector<StaticGeom>& geoms,
                         const CellLists& cells, const StepParams& p, const ContactSet* previous,
                         bool match_static) {
  ContactSet out;
  int n = static_cast<int>(particles.size());
  out.owner_offsets.push_back(0);
  for (int i = 0; i < n; ++i) {
    const Vec3& xi = particles.position[i];
    double ri = particles.radius[i];
    int home = cell_of(xi, p);
    int hx = home % p.grid_nx;
    int hy = (home / p.grid_nx) % p.grid_ny;
    int hz = home / (p.grid_nx * p.grid_ny);
    // particle pairs (i, j > i) in the 27 surrounding cells, z then y then x, index order
    for (int z = hz - 1; z <= hz + 1; ++z) {
      if (z < 0 || z >= p.grid_nz) continue;
      for (int y = hy - 1; y <= hy + 1; ++y) {
        if (y < 0 || y >= p.grid_ny) continue;
        for (int x = hx - 1; x <= hx + 1; ++x) {
          if (x < 0 || x >= p.grid_nx) continue;
          int cell = (z * p.grid_ny + y) * p.grid_nx + x;
          for (int k = cells.cell_start[cell]; k < cells.cell_start[cell + 1]; ++k) {
            int j = cells.cell_particles[k];
            // fixed particles need no rows among themselves (kernels/narrowphase.cl)
            if (j <= i || (particles.inv_mass[i] == 0.0 && particles.inv_mass[j] == 0.0)) continue;
            double rj = particles.radius[j];
            Vec3 d = particles.position[j] - xi;
            double dist = d.norm();
            double gap = dist - ri - rj;
            Vec3 normal = dist > 0.0 ? Vec3(d / dist) : Vec3(0.0, 0.0, 1.0);
            const double closing = (particles.velocity[i] - particles.velocity[j]).dot(normal);
            if (gap >= contact_margin(ri, rj, closing, p)) continue;
            double reduced = ri * rj / (ri + rj);
            out.contacts.push_back(make_contact(i, j, normal, gap, normal * (ri + 0.5 * gap),
                                                -normal * (rj + 0.5 * gap), reduced, p, previous,
                                                true));
          }
        }
      }
    }
    // static geometry (walls, ground) in index order; a wall's radius is infinite, R* = r
    for (int g = 0; g < (particles.inv_mass[i] == 0.0 ? 0 : p.geoms); ++g) {
      Vec3 normal;
      double gap = sphere_geom(xi, ri, geoms[g], &normal);
      if (gap >= contact_margin(ri, ri, particles.velocity[i].dot(normal), p)) continue;
      out.contacts.push_back(make_contact(i, TL_STATIC_BODY(g), normal, gap,
                                          normal * (ri + 0.5 * gap), Vec3::Zero(), ri, p, previous,
                                          match_static));
    }
    out.owner_offsets.push_back(static_cast<int>(out.contacts.size()));
  }
  return out;
}

Adjacency adjacency(const std::vector<Contact>& contacts, int particles) {
  Adjacency out;
  // degrees (both sides of a particle pair), offsets, then lists filled in contact order
  std::vector<int> degree(particles, 0);
  for (const Contact& c : contacts) {
    degree[c.a]++;
    if (c.b >= 0) degree[c.b]++;
  }
  out.offsets = exclusive_scan(degree);
  out.contacts.assign(out.offsets.back(), 0);
  std::vector<int> next(out.offsets.begin(), out.offsets.end() - 1);
  for (int c = 0; c < static_cast<int>(contacts.size()); ++c) {
    out.contacts[next[contacts[c].a]++] = c;
    if (contacts[c].b >= 0) out.contacts[next[contacts[c].b]++] = c;
  }
  return out;
}

// ---- colouring ----

std::vector<int> carried_colours(const std::vector<Contact>& contacts, const Adjacency& adjacency,
                                 const std::vector<int>& previous_colours, int cap) {
  int n = static_cast<int>(contacts.size());
  // last step's colour of each persisting contact
  std::vector<int> carried(n, -1);
  for (int c = 0; c < n; ++c)
    if (contacts[c].previous >= 0) carried[c] = previous_colours.at(contacts[c].previous);
  // kept if below the cap, unless a neighbour of lower index carries the same colour
  std::vector<int> colour = carried;
  for (int& k : colour)
    if (k >= cap) k = -1;
  for (int c = 0; c < n; ++c) {
    for (int body : {contacts[c].a, contacts[c].b}) {
      if (body < 0 || colour[c] < 0) continue;
      for (int k = adjacency.offsets[body]; k < adjacency.offsets[body + 1]; ++k) {
        int d = adjacency.contacts[k];
        if (d < c && carried[d] == carried[c]) colour[c] = -1;
      }
    }
  }
  return colour;
}

std::vector<int> colour_contacts(const std::vector<Contact>& contacts, const Adjacency& adjacency,
                                 int* rounds, std::vector<int> start) {
  int n = static_cast<int>(contacts.size());
  std::vector<int> colour = start.empty() ? std::vector<int>(n, -1) : std::move(start);
  int round = 0;
  for (int remaining = n; remaining > 0; ++round) {
    // every round reads the colours as they were when it began
    std::vector<int> before = colour;
    int uncoloured = 0;
    for (int c = 0; c < n; ++c) {
      if (before[c] >= 0) continue;
      unsigned priority = contact_priority(static_cast<unsigned>(c));
      uint64_t used = 0;
      bool outranked = false;
      // neighbours through both dynamic bodies: an uncoloured one of higher priority goes
      // first; coloured ones take their colour off the table
      for (int body : {contacts[c].a, contacts[c].b}) {
        if (body < 0 || outranked) continue;
        for (int k = adjacency.offsets[body]; k < adjacency.offsets[body + 1]; ++k) {
          int d = adjacency.contacts[k];
          if (d == c) continue;
          if (before[d] < 0) {
            if (contact_priority(static_cast<unsigned>(d)) > priority) {
              outranked = true;
              break;
            }
          } else {
            used |= uint64_t(1) << before[d];
          }
        }
      }
      if (outranked) {
        ++uncoloured;
        continue;
      }
      // smallest free colour
      int k = 0;
      while (k < TL_MAX_COLOURS && ((used >> k) & 1u)) ++k;
      if (k == TL_MAX_COLOURS)
        throw Error("reference colouring: contact " + std::to_string(c) + " needs more than " +
                    std::to_string(TL_MAX_COLOURS) + " colours");
      colour[c] = k;
    }
    if (uncoloured >= remaining)
      throw Error("reference colouring made no progress in round " + std::to_string(round));
    remaining = uncoloured;
  }
  if (rounds != nullptr) *rounds = round;
  return colour;
}

Partition partition_by_colour(const std::vector<int>& colours) {
  Partition out;
  int n = static_cast<int>(colours.size());
  // count each colour, starts by prefix sum, then place contacts in index order
  std::vector<int> counts(TL_MAX_COLOURS, 0);
  for (int k : colours) counts[k]++;
  out.colour_start = exclusive_scan(counts);
  std::vector<int> next(out.colour_start.begin(), out.colour_start.end() - 1);
  out.order.assign(n, 0);
  out.row_of_contact.assign(n, 0);
  for (int c = 0; c < n; ++c) {
    int row = next[colours[c]]++;
    out.order[row] = c;
    out.row_of_contact[c] = row;
  }
  // trimmed to the colours in use (the last entry stays the total)
  while (out.colour_start.size() > 2 && out.colour_start[out.colour_start.size() - 2] == n)
    out.colour_start.pop_back();
  return out;
}

Partition identity_partition(int n_contacts) {
  Partition out;
  for (int c = 0; c < n_contacts; ++c) {
    out.order.push_back(c);
    out.row_of_contact.push_back(c);
  }
  out.colour_start = {0, n_contacts};
  return out;
}

Partition interleaved_partition(int n_contacts, int lanes) {
  // block j holds contacts [floor(j n / lanes), floor((j + 1) n / lanes)); row after row takes
  // the next contact of each block that still has one, blocks in order
  std::vector<std::vector<int>> blocks(lanes);
  for (int j = 0; j < lanes; ++j) {
    const int begin = static_cast<int>(std::int64_t(j) * n_contacts / lanes);
    const int end = static_cast<int>(std::int64_t(j + 1) * n_contacts / lanes);
    for (int c = begin; c < end; ++c) blocks[j].push_back(c);
  }
  Partition out;
  out.row_of_contact.assign(n_contacts, -1);
  for (size_t p = 0; out.order.size() < static_cast<size_t>(n_contacts); ++p)
    for (const std::vector<int>& block : blocks)
      if (p < block.size()) {
        out.row_of_contact[block[p]] = static_cast<int>(out.order.size());
        out.order.push_back(block[p]);
      }
  out.colour_start = {0, n_contacts};
  return out;
}

Partition run_partition(const std::vector<Contact>& contacts, int particles, int parts, int lanes) {
  if (parts < 1 || parts > kMaxSweepParts || particles < 1 || lanes < 1)
    throw Error("reference run_partition: " + std::to_string(parts) + " parts of " +
                std::to_string(particles) + " particles in " + std::to_string(lanes) +
                " blocks (want 1 to kMaxSweepParts parts, particles and blocks)");
  // each contact's run: its dynamic bodies' part when they share one, else the run of the
  // smallest aligned group of parts that holds both (kernels/dem_types.h)
  const auto part_of = [&](int body) {
    return static_cast<int>(std::int64_t(body) * parts / particles);
  };
  std::vector<std::vector<int>> runs(tl_runs(parts));
  for (size_t c = 0; c < contacts.size(); ++c) {
    const int pa = part_of(contacts[c].a);
    const int pb = contacts[c].b >= 0 ? part_of(contacts[c].b) : pa;
    runs[tl_run_of(pa, pb, parts)].push_back(static_cast<int>(c));
  }
  // run after run, each laid out as a whole system of its contacts is
  Partition out;
  out.row_of_contact.assign(contacts.size(), -1);
  out.colour_start = {0};
  for (const std::vector<int>& run : runs) {
    const int begin = static_cast<int>(out.order.size());
    const Partition within = interleaved_partition(static_cast<int>(run.size()), lanes);
    for (int row = 0; row < static_cast<int>(run.size()); ++row) {
      const int c = run[within.order[row]];
      out.order.push_back(c);
      out.row_of_contact[c] = begin + row;
    }
    out.colour_start.push_back(static_cast<int>(out.order.size()));
  }
  return out;
}

// ---- rows ----

std::vector<Row> prepare_rows(const std::vector<Contact>& contacts, const std::vector<int>& order,
                              const Particles& bodies, const StepParams& p, bool warm_start) {
  std::vector<Row> rows;
  rows.reserve(order.size());
  double h = p.dt;
  for (int c : order) {
    const Contact& con = contacts[c];
    const Vec3& n = con.normal;
    BodyVelocity a = body_velocity(bodies, con.a);
    BodyVelocity b = body_velocity(bodies, con.b);

    // normal velocity before the step, and the overlap predicted at its end
    double un = n.dot(b.v - a.v);
    double overlap = std::max(std::max(-con.gap, -con.gap - h * un),
                              p.overlap_floor_rel * con.reduced_radius);
    // secant hertz compliance epsilon = 1 / (k_n sqrt(overlap)), SPOOK coefficients (the same
    // row for speculative contacts, as kernels/solver.cl explains)
    double compliance = 1.0 / (con.stiffness * std::sqrt(overlap));
    double upsilon = 1.0 / (1.0 + 4.0 * p.damping_tau / h);
    double sigma = 4.0 * compliance * upsilon / (h * h);
    double rhs = -(4.0 / h) * upsilon * con.gap + upsilon * un;

    // effective masses: lever arms are parallel to n, so normal rows see no rotation
    double inv_m = a.inv_mass + b.inv_mass;
    double d_t = inv_m + a.inv_inertia * con.arm_a.squaredNorm() +
                 b.inv_inertia * con.arm_b.squaredNorm();
    double d_r = a.inv_inertia + b.inv_inertia;

    // cohesion: a particle pair closer than margin_rel R* holds a tensile impulse
    // up to h F_c, F_c = cohesion R*^2 (kernels/solver.cl explains the margin)
    // (the reach is compared in float, as the kernel does, so a pair at the boundary decides alike)
    const float reach = static_cast<float>(p.margin_rel) * static_cast<float>(con.reduced_radius);
    double cohesion = con.b >= 0 && static_cast<float>(con.gap) <= reach
                          ? h * p.cohesion * con.reduced_radius * con.reduced_radius
                          : 0.0;
    // rolling resistance: between grains the gravel's, against static geometry the ground's
    const double rolling = con.b >= 0 ? p.rolling : p.ground_rolling;

    // warm start: last step's impulses carried into the new frame, within the new cones
    double ln = 0.0;
    Vec3 lt = Vec3::Zero();
    Vec3 lr = Vec3::Zero();
    if (warm_start) {
      ln = std::max(con.impulse_n, -cohesion);
      const Vec3& old_t = con.impulse_t;
      Vec3 projected = old_t - old_t.dot(n) * n;
      double pm = projected.norm();
      lt = pm > 0.0 ? Vec3(projected * (std::min(old_t.norm(), p.friction * (ln + cohesion)) / pm))
                    : Vec3::Zero();
      // rolling onto the new disc, twist about the new normal clamped
      double rmax = rolling * con.reduced_radius * (ln + cohesion);
      double twist = std::clamp(con.impulse_r.dot(n), -rmax, rmax);
      Vec3 roll = con.impulse_r - con.impulse_r.dot(n) * n;
      double rm = roll.norm();
      if (rm > rmax) roll *= rmax / rm;
      lr = roll + twist * n;
    }

    Row row;
    row.normal = n;
    row.rhs = rhs;
    row.arm_a = con.arm_a;
    // the inverse effective masses times the relaxation omega (kernels/solver.cl explains)
    row.inv_dn = p.relaxation / (inv_m + sigma);
    row.arm_b = con.arm_b;
    row.sigma = sigma;
    row.impulse_n = ln;
    row.impulse_t = lt;
    row.impulse_r = lr;
    row.inv_dt = d_t > 0.0 ? p.relaxation / d_t : 0.0;
    row.friction = p.friction;
    row.rolling_limit = rolling * con.reduced_radius;
    row.inv_dr = d_r > 0.0 ? p.relaxation / d_r : 0.0;
    row.cohesion = cohesion;
    row.a = con.a;
    row.b = con.b;
    row.contact = c;
    rows.push_back(row);
  }
  return rows;
}

// ---- velocities ----

void apply_gravity(Particles& bodies, const StepParams& p) {
  for (size_t i = 0; i < bodies.size(); ++i)
    if (bodies.inv_mass[i] > 0.0) bodies.velocity[i] += p.dt * p.gravity;
}

void apply_row_impulses(const std::vector<Row>& rows, const Adjacency& adjacency,
                        const std::vector<int>& row_of_contact, Particles& bodies) {
  for (int i = 0; i < static_cast<int>(bodies.size()); ++i) {
    // sum the impulses of body i's rows in contact order: -P on a, +P on b
    Vec3 dv = Vec3::Zero();
    Vec3 dw = Vec3::Zero();
    for (int k = adjacency.offsets[i]; k < adjacency.offsets[i + 1]; ++k) {
      const Row& row = rows[row_of_contact[adjacency.contacts[k]]];
      bool is_a = row.a == i;
      double s = is_a ? -1.0 : 1.0;
      const Vec3& arm = is_a ? row.arm_a : row.arm_b;
      Vec3 impulse = row.impulse_n * row.normal + row.impulse_t;
      dv += s * impulse;
      dw += s * (arm.cross(impulse) + row.impulse_r);
    }
    bodies.velocity[i] += bodies.inv_mass[i] * dv;
    bodies.omega[i] += bodies.inv_inertia[i] * dw;
  }
}

void pgs_colour(std::vector<Row>& rows, int begin, int end, Particles& bodies) {
  // rows of one colour share no dynamic body, so solving them in turn equals the parallel kernel
  for (int k = begin; k < end; ++k) {
    Row& row = rows[k];
    BodyVelocity a = body_velocity(bodies, row.a);
    BodyVelocity b = body_velocity(bodies, row.b);
    SolveMasses m{a.inv_mass, a.inv_inertia, b.inv_mass, b.inv_inertia,
                  row.inv_dn,  row.inv_dt,    row.inv_dr};
    Vec3 d_lin, d_ang;
    solve_contact(row, a.v, a.w, b.v, b.w, m, &d_lin, &d_ang);
    bodies.velocity[row.a] = a.v;
    bodies.omega[row.a] = a.w;
    if (row.b >= 0) {
      bodies.velocity[row.b] = b.v;
      bodies.omega[row.b] = b.w;
    }
  }
}

void pgs_sweep(std::vector<Row>& rows, const std::vector<int>& colour_start, Particles& bodies) {
  for (size_t k = 0; k + 1 < colour_start.size(); ++k)
    pgs_colour(rows, colour_start[k], colour_start[k + 1], bodies);
}

void jacobi_iteration(std::vector<Row>& rows, const Adjacency& adjacency,
                      const std::vector<int>& row_of_contact, Particles& bodies) {
  int n_rows = static_cast<int>(rows.size());
  std::vector<Vec3> delta_lin(n_rows), delta_ang(n_rows);
  // every row against the same velocities, each body's mass split among its contacts
  for (int k = 0; k < n_rows; ++k) {
    Row& row = rows[k];
    BodyVelocity a = body_velocity(bodies, row.a);
    BodyVelocity b = body_velocity(bodies, row.b);
    double na = adjacency.degree(row.a);
    double nb = row.b >= 0 ? adjacency.degree(row.b) : 0.0;
    double ima = na * a.inv_mass, iia = na * a.inv_inertia;
    double imb = nb * b.inv_mass, iib = nb * b.inv_inertia;
    double d_t = ima + iia * row.arm_a.squaredNorm() + imb + iib * row.arm_b.squaredNorm();
    double d_r = iia + iib;
    SolveMasses m{ima, iia, imb, iib, 1.0 / (ima + imb + row.sigma), d_t > 0.0 ? 1.0 / d_t : 0.0,
                  d_r > 0.0 ? 1.0 / d_r : 0.0};
    solve_contact(row, a.v, a.w, b.v, b.w, m, &delta_lin[k], &delta_ang[k]);
  }
  // each body gathers its rows' impulse changes in contact order
  for (int i = 0; i < static_cast<int>(bodies.size()); ++i) {
    Vec3 dv = Vec3::Zero();
    Vec3 dw = Vec3::Zero();
    for (int k = adjacency.offsets[i]; k < adjacency.offsets[i + 1]; ++k) {
      int r = row_of_contact[adjacency.contacts[k]];
      bool is_a = rows[r].a == i;
      double s = is_a ? -1.0 : 1.0;
      const Vec3& arm = is_a ? rows[r].arm_a : rows[r].arm_b;
      dv += s * delta_lin[r];
      dw += s * (arm.cross(delta_lin[r]) + delta_ang[r]);
    }
    bodies.velocity[i] += bodies.inv_mass[i] * dv;
    bodies.omega[i] += bodies.inv_inertia[i] * dw;
  }
}

std::vector<double> row_residuals(const std::vector<Row>& rows, const Particles& bodies,
                                  double relaxation) {
  std::vector<double> out;
  out.reserve(rows.size());
  for (const Row& row : rows) {
    BodyVelocity a = body_velocity(bodies, row.a);
    BodyVelocity b = body_velocity(bodies, row.b);
    const Vec3& n = row.normal;
    double ln = row.impulse_n;
    // plain Gauss-Seidel's step whatever the relaxation (kernels/solver.cl explains)
    const double inv_dn = row.inv_dn / relaxation, inv_dt = row.inv_dt / relaxation,
                 inv_dr = row.inv_dr / relaxation;
    // normal: one projection step, times the effective mass
    double un = n.dot(b.v - a.v);
    double rn =
        (contact_law::normal_impulse(ln, row.rhs, un, row.sigma, inv_dn, -row.cohesion) - ln) /
        inv_dn;
    // friction: the same for the tangential impulse (rows with an effective mass only)
    Vec3 u = (b.v + b.w.cross(row.arm_b)) - (a.v + a.w.cross(row.arm_a));
    Vec3 ut = u - u.dot(n) * n;
    double rt = 0.0;
    if (inv_dt > 0.0) {
      Vec3 lt_new = contact_law::friction_impulse(row.impulse_t, ut, inv_dt,
                                                  row.friction * (ln + row.cohesion));
      rt = (lt_new - row.impulse_t).norm() / inv_dt;
    }
    // rolling and twist, turned into a velocity by the lever arm's length
    double rr = 0.0;
    if (inv_dr > 0.0) {
      Vec3 wrel = b.w - a.w;
      const Vec3& lr = row.impulse_r;
      Vec3 lr_new = contact_law::rolling_impulse(lr, wrel, n, inv_dr,
                                                 row.rolling_limit * (ln + row.cohesion));
      rr = (lr_new - lr).norm() / inv_dr * row.arm_a.norm();
    }
    out.push_back(rn * rn + rt * rt + rr * rr);
  }
  return out;
}

double residual(const std::vector<Row>& rows, const Particles& bodies, double relaxation) {
  // the squared residuals' sum over the rows that act (a normal impulse or a residual)
  const std::vector<double> r = row_residuals(rows, bodies, relaxation);
  double sum = 0.0;
  size_t acting = 0;
  for (size_t k = 0; k < rows.size(); ++k) {
    sum += r[k];
    if (r[k] > 0.0 || rows[k].impulse_n != 0.0) ++acting;
  }
  return acting > 0 ? std::sqrt(sum / static_cast<double>(acting)) : 0.0;
}

void store_impulses(const std::vector<Row>& rows, std::vector<Contact>& contacts) {
  for (const Row& row : rows) {
    Contact& c = contacts[row.contact];
    c.impulse_n = row.impulse_n;
    c.impulse_t = row.impulse_t;
    c.impulse_r = row.impulse_r;
  }
}

// ---- positions ----

void integrate(Particles& bodies, const StepParams& p) {
  for (size_t i = 0; i < bodies.size(); ++i) {
    if (bodies.inv_mass[i] <= 0.0) continue;  // fixed particles neither move nor turn
    bodies.position[i] += p.dt * bodies.velocity[i];
    // q += h/2 (omega, 0) q with q stored (x, y, z, w), then renormalised
    const Vec3& w = bodies.omega[i];
    Eigen::Vector4d& q = bodies.rotation[i];
    Eigen::Vector4d dq(w.x() * q.w() + w.y() * q.z() - w.z() * q.y(),
                       -w.x() * q.z() + w.y() * q.w() + w.z() * q.x(),
                       w.x() * q.y() - w.y() * q.x() + w.z() * q.w(),
                       -w.x() * q.x() - w.y() * q.y() - w.z() * q.z());
    q += 0.5 * p.dt * dq;
    q /= q.norm();
  }
}

// ---- one time step ----

namespace {

void sweeps(ReferenceWorld& world, int count) {
  for (int it = 0; it < count; ++it) {
    if (world.settings.sweep == SweepKind::Pgs)
      pgs_sweep(world.rows, world.partition.colour_start, world.particles);
    else
      jacobi_iteration(world.rows, world.adjacency, world.partition.row_of_contact,
                       world.particles);
  }
}
}  // namespace

void step(ReferenceWorld& world) {
  const StepParams& p = world.params;
  const DemSettings& s = world.settings;
  if (world.particles.size() == 0) return;
  // contacts, colours and rows of this step
  world.cells = cell_lists(world.particles, p);
  world.current = find_contacts(world.particles, world.geoms, world.cells, p,
                                world.has_previous ? &world.previous : nullptr);
  const std::vector<Contact>& contacts = world.current.contacts;
  world.adjacency = adjacency(contacts, static_cast<int>(world.particles.size()));
  world.colour_rounds = 0;
  std::vector<int> colours;
  const bool interleaved = s.sweep == SweepKind::Pgs && s.serial_lanes > 0 &&
                           world.one_item_sweeps &&
                           static_cast<int>(contacts.size()) <= s.one_group_rows;
  const bool runs =
      s.sweep == SweepKind::Pgs && s.serial_lanes > 0 && world.one_item_sweeps && !interleaved;
  if (interleaved) {
    // one work-item walks the rows: no colours, none carried to the next step
    world.partition = interleaved_partition(static_cast<int>(contacts.size()), s.serial_lanes);
  } else if (runs) {
    // a work-item per run, level by level: one walk over the runs in turn, no colours
    world.partition = run_partition(contacts, static_cast<int>(world.particles.size()),
                                    world.sweep_parts, s.serial_lanes);
  } else if (s.sweep == SweepKind::Pgs) {
    // last step's colours carried to the contacts that persist, the new ones coloured by rounds
    const bool carry = world.colours_carried && world.has_previous;
    std::vector<int> start;
    if (carry)
      start =
          carried_colours(contacts, world.adjacency, world.previous_colours, world.fresh_colours);
    colours = colour_contacts(contacts, world.adjacency, &world.colour_rounds, std::move(start));
    world.partition = partition_by_colour(colours);
    if (!carry) world.fresh_colours = static_cast<int>(world.partition.colour_start.size()) - 1;
  } else {
    world.partition = identity_partition(static_cast<int>(contacts.size()));
  }
  world.rows = prepare_rows(contacts, world.partition.order, world.particles, p, s.warm_start);
  // velocities: external forces, warm start, then the sweeps (in chunks with a tolerance)
  apply_gravity(world.particles, p);
  if (s.warm_start)
    apply_row_impulses(world.rows, world.adjacency, world.partition.row_of_contact,
                       world.particles);
  world.iterations = 0;
  if (!contacts.empty()) {
    if (s.tolerance <= 0.0) {
      sweeps(world, s.iterations);
      world.iterations = s.iterations;
    } else {
      // up to each look of DemWorld::sweep's schedule, until the residual is below it
      ToleranceSchedule schedule(s.tolerance);
      while (world.iterations < s.iterations) {
        const int chunk = std::min(schedule.next_look(), s.iterations) - world.iterations;
        sweeps(world, chunk);
        world.iterations += chunk;
        if (schedule.look(world.iterations, residual(world.rows, world.particles, p.relaxation)))
          break;
      }
    }
  }
  // keep the impulses for the next warm start, move the particles
  store_impulses(world.rows, world.current.contacts);
  integrate(world.particles, p);
  world.previous = world.current;
  world.has_previous = true;
  world.colours_carried =
      s.sweep == SweepKind::Pgs && !interleaved && !runs &&
      carry_colours_after(static_cast<int>(world.partition.colour_start.size()) - 1,
                          world.fresh_colours);
  world.previous_colours = std::move(colours);
}

}  // namespace talus::reference
