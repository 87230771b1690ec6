// Settings of the particle (type-D) stepper: SPEC §2.1-2.2.
#pragma once
#include <string>

#include "solvers/particles.hpp"

namespace talus {

// the two sweep strategies over contact rows, behind one interface (solvers/contact_sweep.hpp)
enum class SweepKind { Pgs, Jacobi };

const char* sweep_name(SweepKind kind);
// "pgs" or "jacobi"; throws InputError naming `field` otherwise
SweepKind parse_sweep(const std::string& text, const std::string& field);

// A carried colouring grows: a persisting contact keeps its colour and a new one takes the
// smallest its neighbours leave, which over many steps spreads a bed's colours towards the
// contact graph's degree (settle10k: 10 colours fresh, 19 after 300 carried steps), and each
// colour is one more launch per sweep. A step whose colouring has more than this many times the
// colours of the last fresh one makes the next step colour afresh (DemWorld::colour_contacts,
// its reference twin; the factor measured in bench/RESULTS.md, 2026-11-27)
inline constexpr double kCarriedColourGrowth = 1.5;
inline bool carry_colours_after(int colours, int fresh_colours) {
  return colours <= kCarriedColourGrowth * fresh_colours;
}

// rows up to which PGS sweeps all colours in one work-group (kernels/solver.cl
// pgs_sweeps_one_group), a launch per sweep instead of one per colour: below it the launches
// cost more than one compute unit's loss of the others (PoCL on 2 cores: gain at 3,440 rows,
// loss at 30,370; bench/RESULTS.md, 2026-11-27)
inline constexpr int kPgsOneGroupRows = 4096;

// blocks a serially walked system's rows interleave (DemSettings::serial_lanes): contact order (1
// block) swept FB35-G200's zone slower than 8 blocks (1.46-1.56 against 1.27-1.34 ms a step, each
// row waiting on the velocities the row before wrote), 4 and 16 blocks within the noise of 8. The
// gain over the colours is the colouring's time (FB35-G200 0.25 -> 0.09 ms a step, HD27-G100 0.71
// -> 0.48); the sweeps cost the same per row within this VM's noise (bench/RESULTS.md 2026-12-02)
inline constexpr int kSerialLanes = 8;
// more blocks than this interleave nothing a core can overlap (its window holds a few rows)
inline constexpr int kMaxSerialLanes = 1024;
// the most parts a large system's rows are walked in (DemSettings::sweep_parts): their runs, all
// levels (kernels/dem_types.h tl_runs: 63 for 32 parts), are partitioned as colours are, at most
// TL_MAX_COLOURS of them (a static_assert in solvers/dem_world.cpp)
inline constexpr int kMaxSweepParts = 32;

// SPOOK damping times a study may ask for [s] (talus run --damping-time for the particle contacts,
// --interface-damping-time for the type-G aggregate's interfaces): from 0.1 ms, the shortest
// timestep a study may take, to 0.5 s, the time a grain dropped from the bucket's height (1.2 m)
// takes to land; a contact damped more slowly than that never settles within a dig's phase
inline constexpr double kMinDampingTime = 1e-4;
inline constexpr double kMaxDampingTime = 0.5;

// partners per particle the narrow phase's count pass keeps for its write pass
// (DemSettings::narrow_phase_slots; measured in docs/dem.md "Narrow phase")
inline constexpr int kNarrowPhaseSlots = 12;
// more slots than a particle can own contacts only cost memory (a sphere touches at most 12 of its
// size; speculative rows add a few tens)
inline constexpr int kMaxNarrowPhaseSlots = 256;

struct DemSettings {
  double dt = 1.0e-3;       // timestep h [s]
  int iterations = 50;      // sweeps per step (upper bound when tolerance > 0)
  bool warm_start = true;   // start from last step's impulses of persistent contacts
  // stop early once the RMS row residual [m/s] falls below this (looked at where
  // solvers/tolerance_schedule says); 0 runs all iterations, as the paper's fixed N_it. The coupled
  // dig (solvers/split_solver) applies it to each outer pass's sweeps
  double tolerance = 0.0;
  SweepKind sweep = SweepKind::Pgs;
  // PGS sweeps systems of at most this many rows in one work-group, larger ones a launch per
  // colour, or on a CPU device in runs (sweep_parts). With colours the same bits either way, only
  // the speed differs by device; on a CPU device the layouts differ (serial_lanes, sweep_parts):
  // 0 never, INT_MAX always
  int one_group_rows = kPgsOneGroupRows;
  // where the one-group sweep is one work-item walking the rows (a CPU device), a system of at
  // most one_group_rows rows is a serial Gauss-Seidel sweep and needs no colours: its rows are then
  // laid out in contact order cut into this many blocks, taken one of each block in turn
  // (kernels/colouring.cl interleaved_order), and the colouring is skipped. Another order than
  // the colours', so other bits than a GPU gives; 0 colours every system as a GPU does, large ones
  // too (no runs; the one-group and per-colour paths then give the same bits)
  int serial_lanes = kSerialLanes;
  // where the sweep walks rows with one work-item (a CPU device) and serial_lanes > 0, a system
  // of more than one_group_rows rows is cut into this many parts by particle index: a contact
  // whose dynamic bodies lie in one part belongs to its run, one across parts to the run of the
  // smallest aligned group of parts holding both (kernels/dem_types.h tl_run_of). Each sweep walks
  // the runs level by level, a level's runs side by side, one work-item each; each run's rows
  // interleaved as serial_lanes says. No colouring, and another order than the colours' (other
  // bits); 0: one part per compute unit of the device (Device::compute_units, at most
  // kMaxSweepParts), so the bits of a large system depend on the device's core count (and differ
  // between PoCL's in-thread device, 1 compute unit, and its threaded one): a fixed count gives
  // the same bits on any CPU device. 1 to kMaxSweepParts
  int sweep_parts = 0;
  Vec3 gravity = Vec3(0.0, 0.0, -9.81);  // [m/s^2]
  // pairs closer than margin_rel * min(r_a, r_b) get a (speculative) contact row: it never
  // pulls them together, and with damping it brakes an approach that would close more than
  // about half the gap within one step (kernels/solver.cl prepare_rows)
  double margin_rel = 0.05;
  // smallest overlap used in the secant Hertz compliance, as a fraction of R*: a new contact
  // is stiff from its first step instead of infinitely soft (SPEC §2.2 "guard delta -> 0")
  double overlap_floor_rel = 1.0e-4;
  // the fastest particle speed to expect [m/s]: pairs within 2 h max_speed of touching get a
  // speculative row, so particles moving more than the margin in one step cannot tunnel into
  // each other (large steps, fast bucket). 0: off (the margin alone)
  double max_speed = 0.0;
  // false: every pair within 2 h max_speed gets a speculative row (the fastest particle's reach,
  // also for grains at rest side by side); true: each pair's own, 2 h (its closing speed + |g| h)
  // and at most that, so a bed at rest makes no speculative rows (kernels/narrowphase.cl). Digs
  // set it (DiggingOptions::pair_reach); piles and the DEM's own benchmarks keep the fastest's
  // (docs/dem.md "Speculative reach" has what each was measured on)
  bool pair_reach = false;
  // the relaxation omega of the PGS sweeps over particle rows: each row's projected step is omega
  // times Gauss-Seidel's (projected successive over-relaxation), which leaves the solution where
  // it is and changes how fast the sweeps reach it; 1 is plain PGS. In (0, 2). The Jacobi sweeps
  // (their own split masses) and the bucket's rows do not use it (docs/dem.md "Relaxation")
  double relaxation = 1.0;
  // the partners of each particle the narrow phase's count pass keeps for its write pass [per
  // particle, 4 bytes each]: a particle with at most this many contacts it owns is written from
  // them, one with more is visited again (the same contacts and bits either way; 0: every
  // particle visited twice). 12 held every particle of the piles and digs measured (they own at
  // most 9-11; docs/dem.md "Narrow phase")
  int narrow_phase_slots = kNarrowPhaseSlots;
};

// the smallest relaxation accepted: below it the sweeps barely move (and far below, the float the
// device gets is zero or subnormal, which a GPU flushes to zero)
inline constexpr double kMinRelaxation = 0.01;
// whether kMinRelaxation <= omega < 2 as the device's float (projected SOR converges in (0, 2))
bool relaxation_in_range(double omega);
// throws InputError naming `field` unless omega is in range, and unless it is 1 with the Jacobi
// sweep, which does not use it (its split masses are its own)
void check_relaxation(double omega, SweepKind sweep, const std::string& field);

}  // namespace talus
