// Avalanching of the type-G terrain's surface (issue 14, SPEC §2.5): where the slope between two
// neighbouring columns is steeper than the angle of repose, soil slides from the higher to the
// lower one until the slope relaxes to it. What the bucket leaves behind (a cut face steeper than
// the gravel can stand, soil dropped back on the pile) comes to rest at the repose angle.
//
// The rule (the reference engine's documented one; the paper gives none): between columns a and b,
// h apart (the four neighbours of each column), the excess height Δh − h tan θ over the repose
// slope decays by a fraction f each step, f / 2 of it leaving the higher column and landing on the
// lower one. The engine moves f = 0.1 of the excess per step at its usual 60 Hz; talus states the
// same decay per second, k = −ln(1 − 0.1) / (1/60 s) = 6.3 /s, f = 1 − exp(−k Δt), so the surface
// relaxes at the same speed at every level's timestep up to G200 (G200's 20 ms: f = 0.12; G50's
// 5 ms: 0.031). f is capped at 0.25: a column with four lower neighbours then gives at most half
// its excess over the steepest, so no step overshoots into a reversed slope; at G400's 50 ms the
// cap holds (1 − exp(−6.3 × 0.05) = 0.27), so G400's surface relaxes at −ln 0.75 / 0.05 = 5.75 /s.
//
// The soil keeps its mass and compaction: it leaves the top of the higher column (terrain's
// `take`) and is laid on the lower one at the compaction it had (`deposit`). All exchanges of a
// step are computed from the heights at its start and applied in a fixed order (every take, then
// every deposit, by column index), so the result does not depend on a sweep order and is the same
// on every run.
#pragma once
#include <vector>

#include "terrain/voxel_terrain.hpp"

namespace talus {

struct AvalancheOptions {
  double repose_deg = 32.0;  // the gravel's angle of repose (paper §4.4: internal friction 32 deg)
  double rate = 6.3;         // decay rate of the excess slope [1/s] (see above)
};

struct AvalancheStep {
  double moved_mass = 0.0;    // soil that slid this step [kg]
  int slopes = 0;             // neighbour pairs steeper than the repose angle at the step's start
  double steepest_deg = 0.0;  // the steepest slope between neighbours at the step's start
};

// the options' one contract, checked by avalanche and by the multiscale terrain before a dig:
// throws talus::InputError naming the field for a repose angle outside (0, 90) deg or a rate
// that is not a finite number >= 0
void check_avalanche_options(const AvalancheOptions& options);

// one step of avalanching over the whole terrain; throws talus::Error for a non-positive timestep,
// a negative rate or a repose angle outside (0, 90) deg. `closed` (one flag per column, index
// j nx + i), when given, marks the columns that take no soil: where a tool's body stands on the
// surface (terrain/multiscale_terrain), the slope into it does not relax, as soil cannot slide
// into the space the body fills; a closed column still gives soil to open lower neighbours
AvalancheStep avalanche(VoxelTerrain& terrain, double dt, const AvalancheOptions& options = {},
                        const std::vector<char>* closed = nullptr);

}  // namespace talus
