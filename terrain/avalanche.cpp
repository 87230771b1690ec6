#include "terrain/avalanche.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "host/error.hpp"

namespace talus {
namespace {

constexpr double kDegree = M_PI / 180.0;
// the most of a pair's excess one step moves (see the header)
constexpr double kMaxFraction = 0.25;

// the most columns one column gives soil to: its four neighbours
constexpr int kNeighbours = 4;

// soil leaving one column this step: how thick a layer, and to whom (column index, thickness),
// in a fixed array (hundreds of columns give soil every step; a list each cost allocations)
struct Outflow {
  double thickness = 0.0;
  int receivers = 0;
  std::array<std::pair<int, double>, kNeighbours> to;
};

}  // namespace

void check_avalanche_options(const AvalancheOptions& options) {
  if (!(options.repose_deg > 0.0 && options.repose_deg < 90.0))
    throw InputError("avalanche: repose_deg " + std::to_string(options.repose_deg) +
                     " deg is not an angle of repose in (0, 90) deg (the gravel's: 32)");
  if (!(options.rate >= 0.0 && std::isfinite(options.rate)))
    throw InputError("avalanche: rate " + std::to_string(options.rate) +
                     " /s is not a decay rate >= 0 (the reference engine's: 6.3 /s)");
}

AvalancheStep avalanche(VoxelTerrain& terrain, double dt, const AvalancheOptions& options,
                        const std::vector<char>* closed) {
  if (!(dt > 0.0))
    throw Error("avalanche: the timestep " + std::to_string(dt) + " s is not positive");
  check_avalanche_options(options);
  AvalancheStep step;
  const int nx = terrain.nx(), ny = terrain.ny();
  if (closed && closed->size() != static_cast<size_t>(nx) * ny)
    throw Error("avalanche: " + std::to_string(closed->size()) + " closed flags for " +
                std::to_string(nx * ny) + " columns");
  const double h = terrain.cell();
  const double stable = h * std::tan(options.repose_deg * kDegree);  // the steepest height step
  const double f = std::min(kMaxFraction, 1.0 - std::exp(-options.rate * dt));
  // the exchanges, from the heights at the step's start
  const std::vector<double> height = terrain.surface_heights();
  std::vector<Outflow> out(static_cast<size_t>(nx) * ny);
  double steepest = 0.0;
  auto pair = [&](int a, int b) {
    const double dh = height[a] - height[b];
    steepest = std::max(steepest, std::abs(dh));
    const double excess = std::abs(dh) - stable;
    if (!(excess > 0.0)) return;
    ++step.slopes;
    const int from = dh > 0.0 ? a : b, to = dh > 0.0 ? b : a;
    if (closed && (*closed)[to]) return;  // nothing slides into a tool's body
    const double t = 0.5 * f * excess;
    out[from].thickness += t;
    out[from].to[out[from].receivers++] = {to, t};
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int c = j * nx + i;
      if (i + 1 < nx) pair(c, c + 1);
      if (j + 1 < ny) pair(c, c + nx);
    }
  step.steepest_deg = std::atan(steepest / h) / kDegree;
  // every take, then every deposit, by column index
  std::vector<SoilTaken> taken(out.size());
  for (size_t c = 0; c < out.size(); ++c) {
    if (out[c].thickness <= 0.0) continue;
    const int i = static_cast<int>(c) % nx, j = static_cast<int>(c) / nx;
    taken[c] = terrain.take(i, j, height[c] - out[c].thickness, height[c]);
    step.moved_mass += taken[c].mass;
  }
  for (size_t c = 0; c < out.size(); ++c) {
    if (taken[c].mass <= 0.0) continue;
    const double compaction = taken[c].mass / (terrain.bank_density() * taken[c].volume);
    // each receiver its share; the last takes what is left, so the shares add up to the mass
    double left = taken[c].mass;
    const int receivers = out[c].receivers;
    for (int k = 0; k < receivers; ++k) {
      const auto [to, t] = out[c].to[k];
      // (rounding can leave the last a hair below zero when its share is negligible)
      const double m =
          k + 1 < receivers ? taken[c].mass * (t / out[c].thickness) : std::max(0.0, left);
      left -= m;
      if (m > 0.0) terrain.deposit(to % nx, to / nx, m, std::min(compaction, kMaxCompaction));
    }
  }
  return step;
}

}  // namespace talus
