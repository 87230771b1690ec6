#include "terrain/voxel_terrain.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "host/error.hpp"

namespace talus {
namespace {

// a volume this small against a cell's is rounding, not soil: a layer that overshoots a cell's
// room by less still fits, and a cell this close to full is full
constexpr double kVolumeRounding = 1e-12;

// the exact integral of the profile's height over [a, b] [m^2]: the polyline's trapezoids
// clipped to the interval, then its flat top to the rear wall
double profile_integral(const PileProfile& profile, double a, double b) {
  auto clipped = [&](double xa, double za, double xb, double zb) {
    double lo = std::max(a, xa), hi = std::min(b, xb);
    if (hi <= lo || xb <= xa) return 0.0;
    auto z = [&](double x) { return za + (zb - za) * (x - xa) / (xb - xa); };
    return 0.5 * (z(lo) + z(hi)) * (hi - lo);
  };
  double area = 0.0;
  const auto& p = profile.points;
  for (size_t k = 1; k < p.size(); ++k)
    area += clipped(p[k - 1].x(), p[k - 1].z(), p[k].x(), p[k].z());
  if (!p.empty() && profile.rear_wall_x > p.back().x())
    area += clipped(p.back().x(), p.back().z(), profile.rear_wall_x, p.back().z());
  return area;
}

}  // namespace

VoxelTerrain::VoxelTerrain(double x0, double y0, double z0, double cell, int nx, int ny, int nz,
                           double bank_density)
    : x0_(x0), y0_(y0), z0_(z0), h_(cell), nx_(nx), ny_(ny), nz_(nz), rho_bank_(bank_density) {
  if (!(cell > 0.0) || !(bank_density > 0.0) || nx < 1 || ny < 1 || nz < 1)
    throw Error(
        "voxel terrain: the cell size, the bank density and the grid's size must be positive");
  if (static_cast<double>(nx) * ny * nz > kMaxVoxelCells)
    throw Error("voxel terrain: " + std::to_string(nx) + " x " + std::to_string(ny) + " x " +
                std::to_string(nz) + " cells is more than the limit of " +
                std::to_string(static_cast<long>(kMaxVoxelCells)));
  size_t n = static_cast<size_t>(nx) * ny * nz;
  mass_.assign(n, 0.0);
  volume_.assign(n, 0.0);
  column_volume_.assign(static_cast<size_t>(nx) * ny, 0.0);
  full_sums_.assign(static_cast<size_t>(nz) + 1, 0.0);
  for (int k = 0; k < nz; ++k) full_sums_[k + 1] = full_sums_[k] + cell * cell * cell;
}

VoxelTerrain VoxelTerrain::from_profile(const PileProfile& profile,
                                        const VoxelTerrainOptions& options) {
  const std::string where = profile.path.empty() ? std::string("pile profile") : profile.path;
  const double h = options.cell;
  if (!(h >= 1e-3 && h <= 1.0))
    throw InputError(where + ": voxel cell " + std::to_string(h) +
                     " m is outside 1 mm .. 1 m; the type-G levels use 0.05 to 0.4 m");
  if (profile.points.size() < 2)
    throw InputError(where + ": profile_xz_m needs at least two points for a voxel terrain");
  // columns from front_margin ahead of the toe to the rear wall, the last ending on the wall
  double x_back = profile.rear_wall_x;
  double x_front = profile.points.front().x() - options.front_margin;
  int nx = static_cast<int>(std::ceil((x_back - x_front) / h - kVolumeRounding));
  int ny = std::max(1, static_cast<int>(std::lround(profile.width / h)));
  double top = 0.0;
  for (const Vec3& p : profile.points) top = std::max(top, p.z());
  int nz = static_cast<int>(std::ceil((top + options.head_room) / h));
  double cells = static_cast<double>(nx) * ny * nz;
  if (cells > kMaxVoxelCells)
    throw InputError(where + ": profile_xz_m and width_m need " +
                     std::to_string(static_cast<long>(cells)) + " voxels of " + std::to_string(h) +
                     " m, more than the limit of " +
                     std::to_string(static_cast<long>(kMaxVoxelCells)) +
                     "; check the profile's units (metres) or use a coarser level");
  VoxelTerrain terrain(x_back - nx * h, -0.5 * ny * h, 0.0, h, nx, ny, nz, options.bank_density);
  // each column holds the profile's mean height over its x-span, at bank density
  for (int i = 0; i < nx; ++i) {
    double xa = terrain.x0_ + i * h;
    double volume = profile_integral(profile, xa, xa + h) * h;
    if (volume <= 0.0) continue;
    for (int j = 0; j < ny; ++j) terrain.restack(i, j, {{volume * options.bank_density, volume}});
  }
  return terrain;
}

bool VoxelTerrain::column_at(double x, double y, int* i, int* j) const {
  double fi = std::floor((x - x0_) / h_), fj = std::floor((y - y0_) / h_);
  if (!(fi >= 0.0 && fi < nx_ && fj >= 0.0 && fj < ny_)) return false;
  *i = static_cast<int>(fi);
  *j = static_cast<int>(fj);
  return true;
}

double VoxelTerrain::occupancy(int i, int j, int k) const {
  return volume_[index(i, j, k)] / (h_ * h_ * h_);
}

double VoxelTerrain::compaction(int i, int j, int k) const {
  size_t c = index(i, j, k);
  return volume_[c] > 0.0 ? mass_[c] / (rho_bank_ * volume_[c]) : 1.0;
}

double VoxelTerrain::column_mass(int i, int j) const {
  double m = 0.0;
  for (int k = 0; k < nz_; ++k) m += mass_[index(i, j, k)];
  return m;
}

double VoxelTerrain::column_volume(int i, int j) const {
  return column_volume_[static_cast<size_t>(j) * nx_ + i];
}

void VoxelTerrain::sum_column_volume(int i, int j, int first, int end) {
  double v = full_sums_[first];
  for (int k = first; k < std::min(end, nz_); ++k) v += volume_[index(i, j, k)];
  column_volume_[static_cast<size_t>(j) * nx_ + i] = v;
}

int VoxelTerrain::unchanged_cells(int i, int j, double z) const {
  const double cap = h_ * h_ * h_;
  // two cells under z's: a cell's top lies a rounding of h above k h, far below z
  const double below = std::floor((z - z0_) / h_) - 2.0;
  const int first = below > 0.0 ? static_cast<int>(std::min(below, double(nz_))) : 0;
  for (int k = 0; k < first; ++k)
    if (volume_[index(i, j, k)] != cap) return k;
  return first;
}

double VoxelTerrain::total_mass() const {
  // column by column, then over the columns: a fixed order, so the same bits on every run
  double m = 0.0;
  for (int j = 0; j < ny_; ++j)
    for (int i = 0; i < nx_; ++i) m += column_mass(i, j);
  return m;
}

std::vector<double> VoxelTerrain::surface_heights() const {
  std::vector<double> heights(static_cast<size_t>(nx_) * ny_);
  for (int j = 0; j < ny_; ++j)
    for (int i = 0; i < nx_; ++i) heights[static_cast<size_t>(j) * nx_ + i] = surface_height(i, j);
  return heights;
}

std::optional<double> VoxelTerrain::surface_at(double x, double y) const {
  return piecewise_linear_height(
      x0_ + 0.5 * h_, y0_ + 0.5 * h_, h_, nx_, ny_,
      [this](int i, int j) { return surface_height(i, j); }, x, y);
}

Heightmap VoxelTerrain::surface(const embree::Device& device) const {
  if (nx_ < 2 || ny_ < 2) throw Error("voxel terrain: a surface needs at least 2 x 2 columns");
  return Heightmap(x0_ + 0.5 * h_, y0_ + 0.5 * h_, h_, nx_, ny_, surface_heights(), device);
}

void VoxelTerrain::restack(int i, int j, const std::vector<Layer>& layers, int first) {
  const double cap = h_ * h_ * h_;
  for (int k = first; k < nz_; ++k) mass_[index(i, j, k)] = volume_[index(i, j, k)] = 0.0;
  int k = first;
  double room = cap;
  for (Layer layer : layers) {
    while (layer.volume > 0.0) {
      if (k >= nz_) {
        sum_column_volume(i, j, first, k);
        throw Error("voxel terrain: a column overflows its " + std::to_string(nz_) + " cells");
      }
      size_t c = index(i, j, k);
      // the layer fits (to rounding): all of it goes here
      if (layer.volume <= room + kVolumeRounding * cap) {
        mass_[c] += layer.mass;
        volume_[c] += layer.volume;
        room -= layer.volume;
        layer.volume = 0.0;
      } else {
        // it does not: the share of its mass that fills the room
        double share = layer.mass * (room / layer.volume);
        mass_[c] += share;
        layer.mass -= share;
        layer.volume -= room;
        room = 0.0;
      }
      // a full cell holds exactly h^3, so the cells under a column's top stay exactly full
      if (room <= kVolumeRounding * cap) {
        volume_[c] = cap;
        ++k;
        room = cap;
      }
    }
  }
  // the cells above k were emptied above (adding their zeros would change no bit)
  sum_column_volume(i, j, first, k + 1);
}

SoilTaken VoxelTerrain::split(int i, int j, double z_lo, double z_hi, std::vector<Layer>* below,
                              std::vector<Layer>* above, int first) const {
  SoilTaken inside;
  const double area = h_ * h_;
  // the interval in the column's own height, clamped to its soil
  double a = std::max(z_lo - z0_, 0.0);
  double b = std::min(z_hi - z0_, column_volume(i, j) / area);
  if (!(b > a)) return inside;
  // each cell's soil spans [k h, k h + V / h^2]: split it into below, inside and above [a, b]
  for (int k = first; k < nz_; ++k) {
    size_t c = index(i, j, k);
    double m = mass_[c], v = volume_[c];
    if (v <= 0.0) break;
    double lo = k * h_, hi = lo + v / area;
    double f_below = std::clamp((a - lo) / (hi - lo), 0.0, 1.0);
    double f_above = std::clamp((hi - b) / (hi - lo), 0.0, 1.0);
    double m_below = m * f_below, m_above = m * f_above;
    double m_inside = m - m_below - m_above;
    if (below && f_below > 0.0) below->push_back({m_below, v * f_below});
    if (above && f_above > 0.0) above->push_back({m_above, v * f_above});
    if (m_inside > 0.0) {
      inside.mass += m_inside;
      inside.volume += v * (1.0 - f_below - f_above);
    }
  }
  inside.bank_volume = inside.mass / rho_bank_;
  return inside;
}

SoilTaken VoxelTerrain::soil_between(int i, int j, double z_lo, double z_hi) const {
  return split(i, j, z_lo, z_hi, nullptr, nullptr);
}

SoilTaken VoxelTerrain::take(int i, int j, double z_lo, double z_hi) {
  // the layers in the terrain's scratch lists, kept between calls (a step's avalanche takes from
  // hundreds of columns, and each fresh list was an allocation)
  std::vector<Layer>& below = scratch_below_;
  std::vector<Layer>& above = scratch_above_;
  below.clear();
  above.clear();
  // the full cells wholly under the interval stay as they are
  const int first = unchanged_cells(i, j, z_lo);
  const SoilTaken taken = split(i, j, z_lo, z_hi, &below, &above, first);
  if (taken.volume <= 0.0 && taken.mass <= 0.0) return taken;
  // what lay above drops onto what lay below
  below.insert(below.end(), above.begin(), above.end());
  restack(i, j, below, first);
  return taken;
}

void VoxelTerrain::deposit(int i, int j, double mass, double compaction) {
  if (!(mass >= 0.0) || !(compaction > 0.0 && compaction <= kMaxCompaction))
    throw Error("voxel terrain: deposit of " + std::to_string(mass) + " kg at compaction " +
                std::to_string(compaction) + " (mass must be >= 0, compaction in (0, " +
                std::to_string(kMaxCompaction) + "])");
  if (mass == 0.0) return;
  double volume = mass / (rho_bank_ * compaction);
  const double cap = h_ * h_ * h_;
  if (column_volume(i, j) + volume > nz_ * cap * (1.0 + kVolumeRounding))
    throw Error("voxel terrain: column (" + std::to_string(i) + ", " + std::to_string(j) +
                ") cannot take " + std::to_string(mass) + " kg more: it would rise above the grid");
  // the column's layers as they are (one per cell) from the first that can change (the full
  // cells under its surface stay), the new soil on top
  const int first = unchanged_cells(i, j, z0_ + column_volume(i, j) / (h_ * h_));
  std::vector<Layer>& layers = scratch_below_;
  layers.clear();
  for (int k = first; k < nz_ && volume_[index(i, j, k)] > 0.0; ++k)
    layers.push_back({mass_[index(i, j, k)], volume_[index(i, j, k)]});
  layers.push_back({mass, volume});
  restack(i, j, layers, first);
}

void VoxelTerrain::save_state(ByteWriter& w) const {
  w.i64(nx_);
  w.i64(ny_);
  w.i64(nz_);
  w.u64(mass_.size());
  w.f64s(mass_.data(), mass_.size());
  w.f64s(volume_.data(), volume_.size());
}

void VoxelTerrain::restore_state(ByteReader& r) {
  const std::int64_t nx = r.i64("voxel grid"), ny = r.i64("voxel grid"), nz = r.i64("voxel grid");
  const std::uint64_t cells = r.u64("voxel grid");
  if (nx != nx_ || ny != ny_ || nz != nz_ || cells != mass_.size())
    throw InputError(r.where() + ": the saved voxel grid is " + std::to_string(nx) + " x " +
                     std::to_string(ny) + " x " + std::to_string(nz) + ", this terrain's " +
                     std::to_string(nx_) + " x " + std::to_string(ny_) + " x " +
                     std::to_string(nz_) +
                     "; restore into a simulation of the same pile and level");
  std::vector<double> mass(cells), volume(cells);
  r.f64s(mass.data(), mass.size(), "voxel masses");
  r.f64s(volume.data(), volume.size(), "voxel volumes");
  // a cell holds at most its cube (h^3; rounding of the volumes that add up to it allowed) and
  // soil only with a volume
  const double cube = h_ * h_ * h_;
  for (size_t c = 0; c < cells; ++c)
    if (!(mass[c] >= 0.0 && volume[c] >= 0.0 && std::isfinite(mass[c]) &&
          volume[c] <= cube * (1.0 + 1e-9) && (mass[c] == 0.0 || volume[c] > 0.0)))
      throw InputError(r.where() + ": a voxel with mass " + std::to_string(mass[c]) +
                       " kg and volume " + std::to_string(volume[c]) + " m^3 (corrupt)");
  mass_ = std::move(mass);
  volume_ = std::move(volume);
  for (int j = 0; j < ny_; ++j)
    for (int i = 0; i < nx_; ++i) sum_column_volume(i, j);
}

}  // namespace talus
