// Host-side description of a granular system: spherical particles, their material, and the
// static geometry (planes, boxes) they rest on. Double precision, SI units.
#pragma once
#include <Eigen/Geometry>
#include <vector>

namespace talus {

using Vec3 = Eigen::Vector3d;

// contact material of particles and walls (one material, as in the paper's gravel)
struct Material {
  double density = 2590.0;  // [kg/m^3] paper §4.3 (gravel)
  // young's modulus [Pa]: not given by the paper (nonsmooth DEM is near-rigid); 1e8 Pa gives
  // overlaps of ~1% of D under 2 m of gravel (documented in docs/dem.md)
  double young = 1.0e8;
  double poisson = 0.3;       // rock-like; enters only through E* = E / (2 (1 - nu^2))
  double friction = 0.3;      // Coulomb mu, paper §4.3
  // rolling resistance mu_r, torque <= mu_r R* lambda_n (SPEC §2.2's definition): the paper's
  // 0.02 (paper §4.3). Its dense gravel then shears with a 40-42 deg peak (the paper's soil: 32 deg
  // internal friction + 8 deg dilatancy), collapses and cuts as the laboratory and the earthmoving
  // equation say; the 32 deg the paper quotes is that soil's internal friction, not the angle of a
  // heap of these spheres (21 deg). talus used 1.0 until issue 11, calibrated to a 32 deg heap: it
  // made the soil 10-20 deg too strong in shear. docs/soil.md has the tests and the sources
  double rolling = 0.02;
  // rolling resistance of a grain against static geometry: the ground and the container's walls,
  // which in the field are gravel-covered, so a grain rests in a pocket between the grains below
  // instead of rolling away on a polished plane. On a square layer of equal grains (the rough base
  // of the soil tests) a sphere rolls out of its pocket on a slope of atan(1/sqrt 2) = 35.3 deg, so
  // the plane holds it below the same slope: mu_r = tan 35.3 deg = 1/sqrt 2 with R* = r (torque
  // balance on a slope, tan theta = mu_r). Issue 11: with the plane at the gravel's 0.02 the toe
  // of a D400 pile ran out 3-4 m as a monolayer of rolling grains
  double ground_rolling = 0.70710678118654752;
  double damping_steps = 2.0; // SPOOK damping time of normal rows in timesteps (tau = n h)
  // bulk tensile strength [Pa] of moist or cohesive soil: touching particles hold a tensile force
  // F_c = pi d^2 cohesion / (phi k) (Rumpf 1962: solid fraction phi, coordination number k; the
  // pile's phi = 1727/2590 and k = 6, d = 4 R* for equal spheres, so F_c = kRumpfPerR2 cohesion
  // R*^2). The paper's gravel is dry: 0. Set by the soil_cohesion effect (vehicle/effect.hpp)
  double cohesion = 0.0;
};

// the bulk density of the field tests' gravel [kg/m^3] (paper §3, SPEC §2.2): what a dense fill
// of the gravel must reach, and the soil's unit weight in the earthmoving equation
inline constexpr double kFieldBulkDensity = 1727.0;

// F_c / (cohesion R*^2) of Rumpf's law for the pile's packing: 16 pi / (phi k) with
// phi = 1727 / 2590 (bulk over particle density, SPEC §2.2) and k = 6 contacts per particle
inline constexpr double kRumpfPerR2 = 16.0 * 3.14159265358979323846 / ((kFieldBulkDensity / 2590.0) * 6.0);

// the paper's gravel (SPEC §2.2)
inline Material gravel() { return Material{}; }

// particles as structure of arrays; orientation quaternions stored (x, y, z, w)
struct Particles {
  std::vector<Vec3> position;
  std::vector<Vec3> velocity;
  std::vector<Vec3> omega;
  std::vector<Eigen::Vector4d> rotation;
  std::vector<double> radius;
  std::vector<double> inv_mass;     // 0 for fixed particles
  std::vector<double> inv_inertia;  // solid sphere: 1 / (2/5 m r^2)

  size_t size() const { return position.size(); }
  // appends a solid sphere of the given density at rest
  void add(const Vec3& x, double r, double density);
  // gives particle i the radius r as a solid sphere of the given density (mass and inertia as
  // add's), keeping where it is and how it moves
  void resize(size_t i, double r, double density);
  // mass of particle i [kg] (0 for fixed ones)
  double mass(size_t i) const { return inv_mass[i] > 0 ? 1.0 / inv_mass[i] : 0.0; }
  // the particles at the indices `order`, in that order (a permutation of 0..size-1, or a subset)
  Particles permuted(const std::vector<size_t>& order) const;
};

// an order that keeps neighbours near each other in memory: by cell of edge `cell` in x, then
// y, then z (columns), which the sweeps' gathers of body velocities reward
std::vector<size_t> spatial_order(const Particles& particles, double cell);

// static geometry: a plane (solid behind it) or an oriented box
struct StaticGeom {
  enum class Type { Plane, Box };
  Type type = Type::Plane;
  Vec3 centre = Vec3::Zero();            // plane: a point on it
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // columns; plane: column 0 = normal
  Vec3 half = Vec3::Zero();              // box half extents

  static StaticGeom plane(const Vec3& point, const Vec3& normal_into_free_side);
  static StaticGeom box(const Vec3& centre, const Vec3& half, const Eigen::Matrix3d& axes);
};

// an axis-aligned region [lo, hi] that bounds where particles live (the broad-phase grid)
struct Bounds {
  Vec3 lo = Vec3::Zero();
  Vec3 hi = Vec3::Zero();
};

// the box of the particles' centres (radii not included); at least one particle, Error otherwise
Bounds centres_box(const Particles& particles);

}  // namespace talus
