// The solid soil of the multiscale terrain (type G, issue 14, SPEC §2.5; Servin, Berglund &
// Nystedt 2021): a regular grid of voxels holding soil mass and compaction, with the surface
// heightfield derived from it.
//
// Data layout. The grid has nx × ny columns of nz cells, cell (i, j, k) spanning
// [x0 + i h, x0 + (i+1) h] × [y0 + j h, ...] × [z0 + k h, ...], stored column by column
// (index (j nx + i) nz + k), so a column's cells lie next to each other: every operation of the
// terrain (dig a column, deposit on it, move soil down a slope) walks one column.
//
// State of a cell: its soil mass m [kg] and its compaction c, the soil's density over the bank
// density (c = 1: the nominal bank state the bulk parameters are given for; excavated soil that
// comes back is looser, c < 1, so it stands taller: swell). The soil fills V = m / (rho_bank c)
// of the cell. Invariant: each column is filled from the bottom, every cell below the highest
// non-empty one is full, so the column's surface lies at z0 + (sum of its V) / h^2 and the grid
// holds no voids. Every operation keeps it: soil is taken from an interval and what lay above
// drops into the gap, soil is laid on top. A column never changes its mass except through an
// operation that hands the same mass on (to another column, or back to the caller), so the
// terrain's mass changes only by what the caller takes or gives: the multiscale model's mass
// balance (voxels + particles + aggregate) is kept by bookkeeping, not by a tolerance.
//
// The container of the type-D piles (terrain/pile: side walls at y = +-width / 2, rear wall,
// flat ground at z = 0, open front) is the grid's boundary: columns span the width between the
// side walls, the last column ends at the rear wall, the first lies `front_margin` in front of
// the pile's toe, where soil pushed off the face lands.
#pragma once
#include <climits>
#include <vector>

#include "host/binary.hpp"
#include "solvers/embree.hpp"
#include "terrain/heightmap.hpp"
#include "terrain/pile.hpp"

namespace talus {

struct VoxelTerrainOptions {
  double cell = 0.2;  // h: the level's particle diameter D [m] (issue 14)
  double bank_density =
      kFieldBulkDensity;      // rho_bank: the field's gravel, 1727 kg/m^3 (paper §4.4)
  double front_margin = 2.0;  // grid ahead of the profile's toe [m]
  double head_room = 1.0;     // cells above the profile's highest point [m]
};

// soil taken out of the terrain: its mass [kg] and the volume it filled there [m^3]
struct SoilTaken {
  double mass = 0.0;
  double volume = 0.0;
  // the bank volume it stands for, mass / rho_bank [m^3]: with `volume`, the swell of soil that
  // was already loose (volume > bank_volume)
  double bank_volume = 0.0;
};

class VoxelTerrain {
 public:
  // an empty grid; throws talus::Error for a non-positive cell, density or size
  VoxelTerrain(double x0, double y0, double z0, double cell, int nx, int ny, int nz,
               double bank_density);

  // the pile of a profile in its container, at bank density: each column holds the profile's
  // mean height over the column's x-span (the exact integral of the polyline), so the terrain's
  // volume is the profile's and its mass the profile's volume times rho_bank (to rounding).
  // Throws InputError naming the option for a cell outside 1 mm .. 1 m or a grid over
  // kMaxVoxelCells cells
  static VoxelTerrain from_profile(const PileProfile& profile, const VoxelTerrainOptions& options);

  // geometry
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  int nz() const { return nz_; }
  double cell() const { return h_; }
  double x0() const { return x0_; }
  double y0() const { return y0_; }
  double z0() const { return z0_; }
  double bank_density() const { return rho_bank_; }
  // the column holding point (x, y), or false off the grid
  bool column_at(double x, double y, int* i, int* j) const;
  double column_x(int i) const { return x0_ + (i + 0.5) * h_; }  // centre [m]
  double column_y(int j) const { return y0_ + (j + 0.5) * h_; }

  // a cell's state
  double mass(int i, int j, int k) const { return mass_[index(i, j, k)]; }
  // its compaction, m / (rho_bank V); 1 for an empty cell
  double compaction(int i, int j, int k) const;
  // the fraction of the cell the soil fills, V / h^3, in [0, 1] (to rounding)
  double occupancy(int i, int j, int k) const;

  // a column: its soil mass [kg], the volume it fills [m^3] and its surface height [m]
  double column_mass(int i, int j) const;
  double column_volume(int i, int j) const;
  double surface_height(int i, int j) const { return z0_ + column_volume(i, j) / (h_ * h_); }
  // the surface at (x, y): the piecewise-linear surface through the columns' tops at their
  // centres (the heightmap's triangles, terrain/heightmap piecewise_linear_height); nullopt
  // outside the columns' centres and on a grid narrower than 2 x 2 columns
  std::optional<double> surface_at(double x, double y) const;
  // the whole terrain's soil mass [kg], summed in a fixed order (the same on every run)
  double total_mass() const;

  // the surface as a heightmap with its Embree scene (nodes at the column centres), for rays,
  // the height under a point and laser scans
  Heightmap surface(const embree::Device& device = embree::Device()) const;
  // the column heights alone, nx × ny, index j nx + i
  std::vector<double> surface_heights() const;

  // what `take` would take, left in place
  SoilTaken soil_between(int i, int j, double z_lo, double z_hi) const;
  // take the soil of column (i, j) between heights z_lo and z_hi (clamped to the column); what
  // lay above z_hi drops by the thickness taken, keeping its compaction. Returns what was taken
  SoilTaken take(int i, int j, double z_lo, double z_hi);
  // lay `mass` [kg] of soil at compaction c (0 < c <= kMaxCompaction) on top of column (i, j);
  // mixes with the soil of a partly filled top cell (the cell's compaction becomes its mass over
  // rho_bank times the volume both fill, so the volumes add). Throws talus::Error when the column
  // would overflow the grid (the caller keeps the mass; nothing is changed)
  void deposit(int i, int j, double mass, double compaction);

  // the cells' soil (mass and volume), for a saved state (digging/saved_state); restore_state
  // reads it into a terrain made from the same profile and cell (InputError naming the reader's
  // place for another grid, a negative or non-finite value)
  void save_state(ByteWriter& w) const;
  void restore_state(ByteReader& r);

 private:
  size_t index(int i, int j, int k) const {
    return (static_cast<size_t>(j) * nx_ + i) * static_cast<size_t>(nz_) + k;
  }
  double x0_, y0_, z0_, h_;
  int nx_, ny_, nz_;
  double rho_bank_;
  // a column's soil, bottom to top, laid into its cells afresh (what `take` and `deposit` end with)
  struct Layer {
    double mass, volume;
  };
  // The cells under `first` are left as they are: a writer that changes only a column's top
  // restacks and sums from there (a G50 step's avalanche takes thin layers off thousands of
  // columns 40-80 cells tall; bench/RESULTS.md 2026-12-01), with the same bits as from the bottom
  // (unchanged_cells says why)
  void restack(int i, int j, const std::vector<Layer>& layers, int first = 0);
  // the column's soil split at heights z_lo < z_hi: what lies inside (returned) and, when asked
  // for, the layers below and above, from cell `first` up (the layers of the cells under it are
  // left out)
  SoilTaken split(int i, int j, double z_lo, double z_hi, std::vector<Layer>* below,
                  std::vector<Layer>* above, int first = 0) const;
  // how many of column (i, j)'s bottom cells a change at height z and above leaves as they are:
  // those exactly full (h^3) and wholly two cells or more under z. Restacking them afresh would
  // lay each back bit for bit (a full cell's mass into an empty cell, its volume exactly h^3), and
  // the column's sum up to them is full_sums_'s, so starting above them changes no bit
  int unchanged_cells(int i, int j, double z) const;
  // column_volume_ of column (i, j) summed afresh from its cells, as every writer of a column
  // ends with: the sum of its `first` bottom cells (full, unchanged_cells) from full_sums_, then
  // the cells up to `end` one by one, bottom to top (those from `end` up must be empty)
  void sum_column_volume(int i, int j, int first = 0, int end = INT_MAX);
  // full_sums_[k]: h^3 added k times, one after another (the sum of k full cells, bottom up)
  std::vector<double> full_sums_;
  std::vector<double> mass_;  // [kg] per cell
  // [m^3] per cell: h^3 exactly in every cell under a column's top one. Volume, not compaction,
  // is stored so that volumes add exactly; compaction is derived, m / (rho_bank V)
  std::vector<double> volume_;
  // [m^3] per column, index j nx + i: the sum of its cells' volumes, bottom to top, kept by every
  // writer of a column (restack, restore_state) so that the surface's readers, several a step
  // over every column, do not add up nz cells each time; the same bits as summing anew
  std::vector<double> column_volume_;
  // the layers `take` and `deposit` restack, reused from call to call
  std::vector<Layer> scratch_below_, scratch_above_;
};

// the most cells a terrain may have: a 100 m pile (kMaxProfileExtent) at the finest level (G50,
// 5 cm) would need far more, so a profile sized by mistake is refused before it is allocated;
// the default pile at 5 cm is 1.5 million cells
inline constexpr double kMaxVoxelCells = 5.0e7;
// the densest soil a cell may hold relative to bank: no packing of equal spheres is denser than a
// solid fraction of 0.7405 (Kepler, Hales 2005), 1918 kg/m^3 with the gravel's 2590 kg/m^3 grains
// (paper §4.3), 1.11 times the field's 1727 kg/m^3; a bound that catches mass laid into too small
// a volume
inline constexpr double kMaxCompaction = 0.7405 * 2590.0 / kFieldBulkDensity;

}  // namespace talus
