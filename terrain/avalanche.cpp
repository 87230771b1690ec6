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

// soil leaving one column this step: which column, how thick a layer, and to whom (column index,
// thickness), in a fixed array (hundreds of columns give soil every step; a list each cost
// allocations)
struct Outflow {
  int column = 0;
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
  // the exchanges, from the heights at the step's start: each column that gives soil, in column
  // order, with its receivers in the order j - 1, i - 1, i + 1, j + 1 (the order in which a sweep
  // over the pairs (c, c + 1), (c, c + nx) meets them, which sums each column's thickness). Only
  // the columns that give are listed: at G50 a dense list of every column's outflow (29,000) cost
  // more than the exchanges (bench/RESULTS.md 2026-12-01)
  const std::vector<double> height = terrain.surface_heights();
  std::vector<Outflow> out;
  double steepest = 0.0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int c = j * nx + i;
      // each pair once (with its right and upper neighbour) for the statistics
      for (const int n : {i + 1 < nx ? c + 1 : -1, j + 1 < ny ? c + nx : -1}) {
        if (n < 0) continue;
        const double dh = std::abs(height[c] - height[n]);
        steepest = std::max(steepest, dh);
        if (dh - stable > 0.0) ++step.slopes;
      }
      // the neighbours this column gives to (nothing slides into a tool's body)
      Outflow flow;
      flow.column = c;
      for (const int n : {j > 0 ? c - nx : -1, i > 0 ? c - 1 : -1, i + 1 < nx ? c + 1 : -1,
                          j + 1 < ny ? c + nx : -1}) {
        if (n < 0 || !(height[c] > height[n])) continue;
        const double excess = std::abs(height[c] - height[n]) - stable;
        if (!(excess > 0.0) || (closed && (*closed)[n])) continue;
        const double t = 0.5 * f * excess;
        flow.thickness += t;
        flow.to[flow.receivers++] = {n, t};
      }
      if (flow.receivers > 0) out.push_back(flow);
    }
  step.steepest_deg = std::atan(steepest / h) / kDegree;
  // every take, then every deposit, by column index
  std::vector<SoilTaken> taken(out.size());
  for (size_t k = 0; k < out.size(); ++k) {
    const int c = out[k].column;
    taken[k] = terrain.take(c % nx, c / nx, height[c] - out[k].thickness, height[c]);
    step.moved_mass += taken[k].mass;
  }
  for (size_t k = 0; k < out.size(); ++k) {
    if (taken[k].mass <= 0.0) continue;
    const double compaction = taken[k].mass / (terrain.bank_density() * taken[k].volume);
    // each receiver its share; the last takes what is left, so the shares add up to the mass
    double left = taken[k].mass;
    const int receivers = out[k].receivers;
    for (int r = 0; r < receivers; ++r) {
      const auto [to, t] = out[k].to[r];
      // (rounding can leave the last a hair below zero when its share is negligible)
      const double m =
          r + 1 < receivers ? taken[k].mass * (t / out[k].thickness) : std::max(0.0, left);
      left -= m;
      if (m > 0.0) terrain.deposit(to % nx, to / nx, m, std::min(compaction, kMaxCompaction));
    }
  }
  return step;
}

}  // namespace talus
