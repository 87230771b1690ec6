// Piles of gravel in a container (SPEC §2.5): the profile is data (data/piles/*.json), so a
// scanned front surface can replace the default one. Particles are emitted on a jittered
// lattice under the (height-stretched) profile and settled under gravity.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "host/progress.hpp"
#include "solvers/dem_world.hpp"
#include "solvers/particles.hpp"
#include "terrain/heightmap.hpp"

namespace talus {

// the pile's cross-section: height z(x) as a polyline from the toe to the rear wall
struct PileProfile {
  std::string name;
  std::string path;  // the file it was read from (for messages; empty if built in code)
  std::string source;
  double width = 6.0;              // container width along y [m]
  std::vector<Vec3> points;        // (x, 0, z) polyline, x increasing
  double rear_wall_x = 0.0;        // [m]

  double height_at(double x) const;   // 0 outside [front toe, rear wall]
  double cross_section() const;       // [m^2]
  double volume() const { return cross_section() * width; }
};

// reads a profile file; InputError names the file and field on bad input (a profile enclosing no
// soil, or with a point farther than kMaxProfileExtent from the origin, included)
PileProfile load_pile_profile(const std::string& path);
// the farthest a profile's point or rear wall may lie from its origin, in x or z, and the widest
// container [m]: a gravel pile stands a few metres high (the field's: 2 m), and far beyond this
// the device's float positions lose the millimetres a contact needs
inline constexpr double kMaxProfileExtent = 100.0;
// the most particles a pile may hold: ten times paper Table 3's finest level (D50, 450,000), so a
// pile sized by mistake (a profile in millimetres, a kilometre-high point) is refused before it
// is filled, not after the machine's memory runs out
inline constexpr double kMaxPileParticles = 4.5e6;
// the particles a pile needs at a level: its volume filled to the emission's solid fraction with
// spheres of the level's diameter
double estimated_pile_particles(const PileProfile& profile, double diameter);
// the DEM's device memory per particle of a settled pile [bytes], all arrays and the largest one
// (an array of contacts): measured 1611 and 439 at D400, 1802 and 486 at D200 (`talus pile`'s
// device_bytes_per_particle and largest_buffer_bytes, 2026-11-27, PoCL; 1611 and 432, 1809 and 487
// with the particle rows in two arrays, 2026-12-02); bounds with 40 % over the measured, for the
// capacities' growth ahead of the sizes (host/device.hpp Buffer)
inline constexpr double kDemDeviceBytesPerParticle = 2500.0;
inline constexpr double kDemLargestBufferBytesPerParticle = 700.0;
// a pile of `particles` on a device with `global_bytes` of memory and `max_allocation_bytes` per
// buffer: InputError from `where` naming the estimate, the device's figure and the fix when it
// would not fit (before, the allocation failed mid-fill in OpenCL, or the host swapped)
void check_device_memory(double particles, std::size_t global_bytes,
                         std::size_t max_allocation_bytes, const std::string& where,
                         const std::string& level);
// data/piles/default.json (looked up next to the sources or the working directory)
PileProfile default_pile_profile();

// the fidelity presets of paper Table 3 (type D)
struct FidelityPreset {
  std::string name;      // "D400", ...
  double diameter;       // D [m]
  double dt;             // [s]
  int iterations;        // N_it
  int paper_particles;   // N_p in paper Table 3
};
const std::vector<FidelityPreset>& fidelity_presets();
// a type-D level; throws InputError listing the known names, and for a type-G name says that it has
// no particles of its own to build or test (what asks for a particle level: piles, soil tests, DEM
// benchmarks)
const FidelityPreset& fidelity_preset(const std::string& name);
// a level of either family, for what runs a scenario (talus run, sweep, synth, diagnose, the
// facade) or the cutting test (talus cut); throws InputError listing both families' names
const FidelityPreset& level_preset(const std::string& name);
// the multiscale levels of paper Table 3 (type G, issue 14): D is the voxel cell and the size of
// the active zone's particles, N_p the most particles the paper's zone held (its "≲")
const std::vector<FidelityPreset>& multiscale_presets();
// the type-G preset of that name, or nullptr
const FidelityPreset* find_multiscale_preset(const std::string& name);
// is the level the multiscale terrain's (a type-G preset)?
bool is_multiscale(const FidelityPreset& preset);
// the device a run of this level steps on: TALUS_DEVICE's choice, preferring a CPU device that
// runs the kernels in the calling thread (DeviceChoice::in_host_thread) for a type-G level of at
// most kInHostThreadParticles particles in paper Table 3 (G400, G200), whose zone's steps are
// mostly hand-overs between threads on PoCL's threaded device (bench/RESULTS.md 2026-11-28 "in
// the host thread"). Type D keeps the default device: its piles are cached under the device's
// name (terrain/pile_cache), and D400 (800) was not measured beyond the noise
DeviceChoice device_choice_for(const FidelityPreset& preset);
// the largest zone, in paper Table 3's particles, stepped in the calling thread: G200 (480; 245
// here) ran in 0.66 of the time; G100 (3,500) in 0.89-0.96 on HD27 and RD21 (1,100-2,100 here)
// but 1.24-1.27 on FB35 (7,300), whose zone keeps both cores busy (bench/RESULTS.md 2026-12-01)
constexpr int kInHostThreadParticles = 1000;
// for what runs several levels on one device (talus sweep): in the calling thread only if every
// level would be
DeviceChoice device_choice_for(const std::vector<const FidelityPreset*>& presets);

// the container: ground, side walls, rear wall (open front)
std::vector<StaticGeom> pile_container(const PileProfile& profile);
// formwork along the rising segments of the profile (boxes in front of the face), held while
// the pile is filled densely and removed before it settles with the gravel's friction
std::vector<StaticGeom> pile_forms(const PileProfile& profile);
// is (x, z) behind every rising face segment (extended upward) and inside the container?
bool behind_faces(const PileProfile& profile, double x, double z);
Bounds pile_bounds(const PileProfile& profile, double diameter);

// particles with diameters uniform in D +- 0.1 D on a jittered lattice behind the faces,
// filled layer by layer from the ground until the solid volume is settled_fraction times the
// profile's volume (the lattice is looser than the bed, so it starts taller than the pile).
// The default, 0.62, is below the field's 1727 / 2590 = 0.667: the settled pile holds about 7 %
// less soil than its profile at the field's density (ProfileFit's mean, about -0.1 m)
inline constexpr double kEmissionSolidFraction = 0.62;
Particles emit_pile_particles(const PileProfile& profile, double diameter, const Material& material,
                              unsigned seed, double settled_fraction = kEmissionSolidFraction);

// bulk density [kg/m^3] from particle positions: the solid volume of spheres whose centres lie
// in the box [lo, hi], over the box volume (a box well inside the bed, away from walls)
double bulk_density(const Particles& particles, const Bounds& box, double particle_density);

}  // namespace talus

namespace talus {

// how much soil the pile holds against its profile, column by column: the particles' mass over
// strips 2 D long (x) in the middle half of the width, divided by the strip's area and the field's
// bulk density (kFieldBulkDensity), is the height the soil would stand at that density. The laser
// reads the grains' tops, which stand about half a grain above this height at D400 (a skimming
// cut meets the soil, not the tops); strips from the profile's front to its rear wall [m]
struct ProfileFit {
  double rms_m = 0.0;   // root mean square of (soil height - profile height)
  double mean_m = 0.0;  // mean of the same: negative when the pile holds less than it was built to
};
ProfileFit bulk_fit_to_profile(const Particles& particles, const PileProfile& profile,
                               double diameter);

// a settled pile: emission, then settling with the preset's timestep
struct PileBuild {
  Particles particles;
  std::vector<StaticGeom> geoms;
  Bounds bounds;
  // the dense fill behind the formwork, friction off: how long it settled and whether it came to
  // rest before the friction went on (simulated [s], RMS particle speed at its end [m/s])
  double fill_time = 0.0;
  bool fill_at_rest = false;
  double fill_rms_speed = 0.0;
  double settle_time = 0.0;  // simulated [s], with the gravel's friction, formwork gone
  bool at_rest = false;
  double rms_speed = 0.0;     // at the end [m/s]
  int settle_iterations = 0;  // sweeps per step while filling and settling
  double bulk_density = 0.0;  // in the flat top's core [kg/m^3]
  double toe_shift = 0.0;     // how far the settled pile was moved to put its toe in place [m]
  ProfileFit soil_fit;        // the placed pile's soil against its profile
  // the DEM's device memory when settling ended [bytes] (DemBuffers::device_bytes): what a dig of
  // this pile needs on the device, before the bucket's own arrays
  std::size_t device_bytes = 0;
  std::size_t largest_buffer_bytes = 0;  // the largest single array of them [bytes]
  // how this pile was had, not part of it (terrain/pile_cache.hpp neither writes nor compares
  // these): read back from the cache, and the cache file it was read from or saved to
  bool from_cache = false;
  std::string cache_file;
};

// the most sweeps per step the rule gives settling (PileBuildOptions::settle_iterations)
inline constexpr int kSettleIterationCap = 100;

struct PileBuildOptions {
  unsigned seed = 1;
  // sweeps per step while filling and settling: 0 takes the rule, the level's N_it capped at
  // kSettleIterationCap (settling needs no precise forces); a positive value is a study's choice,
  // used as it is, above the level's N_it too (issue 11: does the D100 pile stand with more?)
  int settle_iterations = 0;
  double min_time = 1.0;  // [s]
  double max_time = 4.0;  // [s]
  // with a free face (hold_face false), the formwork withdraws from the face at this speed before
  // the pile settles [m/s] (0: removed at once). A study knob of issue 11: on the gravel-covered
  // ground (Material::ground_rolling) the pile's face stood at 29 deg at D400 either way (HD27-D400
  // loaded 2212 kg after an instant removal, 2223 kg after one at 0.5 m/s). A held face keeps its
  // formwork until the dig, so a withdrawal speed with it is refused (build_pile)
  double form_speed = 0.0;
  double form_travel = 2.0;  // how far the formwork withdraws before it is removed [m]
  // move the settled pile along x so that its toe lies where the profile's does (pile_toe): a
  // face that slumps below the profile's angle runs out in front of the designed toe, where the
  // scenario's machine stands; the field's pile was scanned where it lay, so its toe is the fact
  bool place_toe = true;
  // the formwork stays while the pile settles with the gravel's friction and goes only when the
  // pile is used (its geoms leave it out): the face stands at the profile when a dig starts, as
  // the paper's piles were "emitted into a container with a front surface shaped as in the field
  // tests" (paper §4.2). The default since issue 11's seventh part (docs/validation.md): these
  // spheres (mu 0.3, mu_r 0.02) heap at about 20 deg, so a face freed before settling slumps the
  // more the finer the level (25-28 deg at D100 where the field's stood at 32) and HD27 loaded
  // 2.39 / 1.35 / 0.83 t at D400 / D200 / D100; held, 2.72 / 2.35 / 2.69 t (field 2.70 t).
  // false (talus --free-face) settles the pile free after the formwork withdraws (form_speed)
  bool hold_face = true;
};

// the toe of a pile: the first x, from the front, where its surface rises kToeHeight above the
// ground. Of the profile: on its polyline; of particles: on mean_surface over the middle half of
// the container's width in bins of D along x (a lone grain that rolled ahead does not count)
inline constexpr double kToeHeight = 0.2;  // [m], a tenth of the default pile's 2 m (SPEC §2.5)
double profile_toe(const PileProfile& profile);
double particle_toe(const Particles& particles, const PileProfile& profile, double diameter);

// the sweeps per step a pile is filled and settled with at that level under those options
int settle_sweeps(const FidelityPreset& preset, const PileBuildOptions& options);

PileBuild build_pile(Device& dev, const PileProfile& profile, const FidelityPreset& preset,
                     const Material& material, const PileBuildOptions& options, Progress* progress);

// the pile's surface as the field tests measured it before loading: a heightmap of the
// particles (terrain/heightmap.hpp, cell = D) scanned by a 2-D laser in the mid plane y = 0
// from a sensor 3 m in front of the toe and 3 m up; (x, z) points from the front to the rear
struct PileScan {
  std::vector<Eigen::Vector2d> points;
  double face_angle_deg = 0.0;  // least-squares slope of the points between 20% and 80% height
  // how the scanned surface stands against the profile it was built to, over the points between
  // the profile's front and its rear wall: root mean square and mean of (scan - profile) height
  // [m]; a negative mean is a pile standing lower than built (a slumped face)
  double rms_to_profile_m = 0.0;
  double mean_to_profile_m = 0.0;
};
PileScan scan_pile(const Particles& particles, const PileProfile& profile, double diameter);
// the same laser scan of any surface standing on the profile's ground (the type-G terrain's voxels)
PileScan scan_surface(const Heightmap& map, const PileProfile& profile);

}  // namespace talus
