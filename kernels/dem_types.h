// DEM data layouts shared by host C++ (terrain/, solvers/) and the OpenCL kernels.
// Prepended after common.h to every kernel program. All device data is float32.
//
// Particles are stored as structure-of-arrays of float4 so that a kernel touching only
// positions moves only positions:
//   position  xyz = centre [m],             w = radius [m]
//   velocity  xyz = linear velocity [m/s],  w = inverse mass [1/kg] (0 = fixed)
//   omega     xyz = angular velocity [1/s], w = inverse moment of inertia [1/(kg m^2)]
//   rotation  quaternion (x, y, z, w)
#ifndef TALUS_KERNELS_DEM_TYPES_H
#define TALUS_KERNELS_DEM_TYPES_H

// static geometry kinds
#define TL_GEOM_PLANE 0
#define TL_GEOM_BOX 1

// the largest number of colours in the graph colouring of contacts (one bit each in a ulong);
// a sphere has at most ~14 neighbours of similar size, so a contact has < 32 neighbours
#define TL_MAX_COLOURS 64

// Runs (RowLayout::Runs, kernels/colouring.cl contact_part): a large system on a CPU device is cut
// into `parts` ranges of particle indices. A contact within one part belongs to that part's run
// (level 0); one across parts pa < pb to the run of the smallest aligned group of parts that holds
// both: level l = the bit length of pa ^ pb, group pa >> l, parts [g 2^l, (g + 1) 2^l). Runs of one
// level hold disjoint ranges of bodies, so each level's runs are walked side by side (a work-item
// each) and the levels in turn: log2(parts) + 1 launches a sweep, and only the top level's one run
// (the contacts across the middle cut) is walked alone. With a flat boundary instead, every cut's
// contacts would wait for one work-item: 35 % of D200's rows in 16 parts (bench/RESULTS.md
// 2026-12-02 "runs in levels"). Integer arithmetic only, the same in OpenCL C and C++.

// the groups of runs at `level`: ceil(parts / 2^level)
static inline int tl_run_groups(int parts, int level) {
  return (parts + (1 << level) - 1) >> level;
}
// the levels: 0 up to the first with one group
static inline int tl_run_levels(int parts) {
  int level = 0;
  while (tl_run_groups(parts, level) > 1) ++level;
  return level + 1;
}
// the index of the first run of `level` (the runs are numbered level after level)
static inline int tl_run_first(int parts, int level) {
  int first = 0;
  for (int k = 0; k < level; ++k) first += tl_run_groups(parts, k);
  return first;
}
// the runs of `parts` parts, all levels
static inline int tl_runs(int parts) { return tl_run_first(parts, tl_run_levels(parts)); }
// the run of a contact between bodies of parts pa and pb (pb = pa for one with static geometry)
static inline int tl_run_of(int pa, int pb, int parts) {
  int level = 0;
  for (int x = pa ^ pb; x != 0; x >>= 1) ++level;
  return tl_run_first(parts, level) + (pa >> level);
}

// the narrow phase's warm-start matching: last step's particle pairs, its static contacts
#define TL_MATCH_PAIRS 1
#define TL_MATCH_STATIC 2

// a contact's "b" index below zero names static geometry number -1-b
#define TL_STATIC_BODY(geom) (-1 - (geom))

// static geometry: an infinite plane (half-space behind it is solid) or an oriented box
typedef struct {
  tl_float4 centre;   // plane: a point on it; box: the centre [m]
  tl_float4 axis_x;   // plane: unit normal pointing into the free side; box: first unit axis
  tl_float4 axis_y;   // box: second unit axis
  tl_float4 axis_z;   // box: third unit axis
  tl_float4 half_extent;    // box: half extents along the axes [m]
  tl_int type;        // TL_GEOM_PLANE or TL_GEOM_BOX
  tl_int pad0, pad1, pad2;
} TlGeom;

// everything a step's kernels need besides the arrays, passed by value
typedef struct {
  tl_float4 gravity;      // xyz [m/s^2]
  tl_float4 grid_origin;  // xyz lower corner of the broad-phase lattice (the bounds') [m]
  tl_float cell_size;     // edge of a grid cell [m], >= largest diameter + margin
  // the grid's cells: grid_nx x grid_ny x grid_nz of the lattice, from its cell (grid_i0,
  // grid_j0, grid_k0) (DemWorld::set_grid_region: a sub-box where the particles are; 0, 0, 0 and
  // the whole bounds without one). A particle's cell is counted from the lattice's origin, so a
  // sub-box holds each particle in the same lattice cell as the whole grid would
  tl_int grid_nx, grid_ny, grid_nz;
  tl_float dt;            // timestep h [s]
  tl_float young;         // particle Young's modulus E [Pa] (walls: same material)
  tl_float poisson;       // Poisson ratio
  tl_float friction;      // Coulomb friction coefficient mu
  tl_float rolling;       // rolling resistance coefficient mu_r (torque <= mu_r R* lambda_n)
  tl_float damping_tau;   // SPOOK damping time tau [s] of the normal rows
  tl_float margin_rel;    // contact margin as a fraction of the smaller radius
  tl_float overlap_floor_rel;  // smallest overlap (fraction of R*) used for the secant compliance
  tl_int particles;       // number of particles
  tl_int geoms;           // number of static geometries
  tl_float speculative;   // extra contact distance for fast approach, 2 h v_max [m]
  // cohesion of particle pairs closer than margin_rel R*: the tensile force a pair holds is
  // cohesion R*^2 [N]
  // (solvers/particles.hpp Material::cohesion, Rumpf's law); 0 for dry gravel
  tl_float cohesion;
  // rolling resistance of a grain against static geometry (ground, walls): mu_r of
  // solvers/particles.hpp Material::ground_rolling, with R* = r
  tl_float ground_rolling;
  // 1: each pair's speculative reach is its own, 2 h (closing speed + |g| h), at most
  // `speculative` (DemSettings::pair_reach); 0: every pair gets `speculative`
  tl_int pair_reach;
  // the PGS relaxation factor omega in (0, 2): each row's step is omega times the projected
  // Gauss-Seidel step (projected SOR), folded into the rows' inverse effective masses by
  // prepare_rows (DemSettings::relaxation); 1 is plain PGS
  tl_float relaxation;
  tl_int grid_i0, grid_j0, grid_k0;  // the grid's first cell on the lattice (see grid_nx)
  tl_int pad_params[2];
} TlStepParams;

// a contact as found by the narrow phase, grouped by its owner particle a (b > a, or static).
// The impulses persist to the next step for warm starting.
typedef struct {
  tl_float4 normal;     // xyz unit normal from a towards b; w = gap [m] (negative = overlap)
  tl_float4 arm_a;      // xyz lever arm from a's centre to the contact point; w = R* [m]
  tl_float4 arm_b;      // xyz lever arm from b's centre (zero for static b); w = Hertz k_n [N/m^1.5]
  tl_float4 impulse_t;  // xyz friction impulse on b over the step [N s]; w = normal impulse
  tl_float4 impulse_r;  // xyz rolling + twisting impulse (angular, on b) [N m s]; w unused
  tl_int a, b;          // particle indices; b < 0 is static geometry -1-b
  // index in last step's list of the contact with the same (a, b), -1 when new or when there is
  // no last step of these particles: the colouring carries that contact's colour
  // (kernels/colouring.cl carry_colours). Written whatever the matching flags say, since a
  // colour depends on the bodies alone (a static b renumbered still names the same body a)
  tl_int previous;
  tl_int pad1;
} TlContact;

// A particle contact's constraint rows prepared for the sweeps (SPOOK, Hertz), laid out in the
// sweeps' order (colours, interleaved or runs), split in two arrays: what the sweeps only read
// (TlParticleRow, 64 B, one cache line) and the impulses they read and write (TlImpulse, 32 B).
// A sweep's row update so reads 64 + 32 B of row and writes back 32 B (the 112 B TlRow below held
// the impulses at its offset 48, so a row update read 112 B and dirtied 1.25 cache lines of it on
// average: 80 B written back), besides its two bodies. Friction and
// rolling rows act on world vectors: for spheres, and a sphere against a plane or a box, the lever
// arms lie along the normal (kernels/narrowphase.cl emit_pair, emit_static), so each arm is one
// signed length times n and the effective masses are isotropic (one scalar each). The rows carry
// the relaxation omega in their inverse effective masses (TlStepParams::relaxation).
typedef struct {
  tl_float4 normal;  // xyz unit normal from a towards b; w = rhs of the normal row B_n [m/s]
  tl_float4 mass;    // x = omega/D_n, D_n = G M^-1 G^T + Sigma_n; y = Sigma_n [m/(N s)];
                     // z = omega/D_t (friction); w = omega/D_r (rolling)
  tl_float4 law;     // x = mu, y = mu_r R* [m], z = the tensile impulse the contact holds, h F_c
                     // [N s] (0: no cohesion), w = a's lever arm along n [m] (arm_a = w n)
  tl_float arm_b;    // b's lever arm along n [m] (arm_b = arm_b n; 0 for static geometry)
  tl_int a, b;       // bodies (b < 0 static)
  tl_int contact;    // index of the TlContact this row was made from
} TlParticleRow;

// a particle row's impulses over the step, warm-started from the contact's (TlContact)
typedef struct {
  tl_float4 t;  // xyz friction impulse on b [N s]; w = normal impulse lambda_n [N s]
  tl_float4 r;  // xyz rolling + twisting impulse (angular, on b) [N m s]; w unused (0)
} TlImpulse;

// one contact's constraint rows for the bucket and kinematic tools (made on the host:
// solvers/bucket_rows, solvers/kinematic_tool_rows), whose lever arms are not along the normal:
// full arm vectors, the impulses in the row. They carry no relaxation (omega = 1).
typedef struct {
  tl_float4 normal;     // xyz normal; w = rhs of the normal row B_n [m/s]
  tl_float4 arm_a;      // xyz lever arm of a; w = omega/D_n, D_n = G M^-1 G^T + Sigma_n
  tl_float4 arm_b;      // xyz lever arm of b; w = Sigma_n [m/(N s)]
  tl_float4 impulse_t;  // xyz friction impulse; w = normal impulse lambda_n
  tl_float4 impulse_r;  // xyz rolling impulse; w = omega/D_t (friction effective mass)
  tl_float4 coef;       // x = mu, y = mu_r R* [m], z = omega/D_r (rolling effective mass),
                        // w = the tensile impulse the contact holds, h F_c [N s] (0: no cohesion)
  tl_int a, b;          // bodies (b < 0 static)
  tl_int contact;       // index of the TlContact this row was made from
  tl_int pad0;
} TlRow;

#ifdef __OPENCL_VERSION__
// the packed lanes of a row by name, for a row in registers or in global memory alike (the C++
// side decodes a row once, in solvers/contact_rows from_device): ROW_ for a particle row
// (TlParticleRow), TOOL_ROW_ for a bucket's or tool's (TlRow)
#define ROW_RHS(row) ((row).normal.w)
#define ROW_INV_DN(row) ((row).mass.x)
#define ROW_SIGMA(row) ((row).mass.y)
#define ROW_INV_DT(row) ((row).mass.z)
#define ROW_INV_DR(row) ((row).mass.w)
#define ROW_FRICTION(row) ((row).law.x)
#define ROW_ROLLING_LIMIT(row) ((row).law.y)
#define ROW_COHESION(row) ((row).law.z)
#define ROW_ARM_A(row) ((row).law.w)
#define ROW_ARM_B(row) ((row).arm_b)
#define TOOL_ROW_RHS(row) ((row).normal.w)
#define TOOL_ROW_INV_DN(row) ((row).arm_a.w)
#define TOOL_ROW_SIGMA(row) ((row).arm_b.w)
#define TOOL_ROW_IMPULSE_N(row) ((row).impulse_t.w)
#define TOOL_ROW_INV_DT(row) ((row).impulse_r.w)
#define TOOL_ROW_FRICTION(row) ((row).coef.x)
#define TOOL_ROW_ROLLING_LIMIT(row) ((row).coef.y)
#define TOOL_ROW_INV_DR(row) ((row).coef.z)
#endif

// the bucket: one rigid body of the vehicle that particles touch (SPEC §1 steps 3-6). Its rows
// are TlRow with b = TL_BUCKET_BODY and arm_b the lever arm about the bucket's centre of mass;
// they live in their own buffer and are solved one after another by one work-item
// (kernels/bucket.cl), because every one of them shares the bucket and graph colouring would
// give each its own colour
#define TL_BUCKET_BODY (-2147483647)

// the bucket's state inside the sweeps: its twist, and its articulated mobility from the direct
// vehicle solver (the 6x6 Schur complement: twist change per impulse wrench [P; L] about the
// centre of mass, all joints and motors of the machine active), row-major
typedef struct {
  tl_float4 velocity;      // xyz linear velocity of the centre of mass [m/s]; w unused
  tl_float4 omega;         // xyz angular velocity [1/s]; w unused
  tl_float mobility[36];   // W [m/(N s)], [1/(N m s)]; row-major 6x6
} TlBucketBody;

#endif
