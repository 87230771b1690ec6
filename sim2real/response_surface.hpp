// A local response surface of a one-parameter objective: the window around the coarse scan's best
// point, and the parabola fitted to the objective's samples in it by least squares (issue 17).
//
// Why: a digging simulation is chaotic in its parameters (the grains' arrangement switches with
// any change), so the likelihood along a parameter is a smooth trend plus a rough part that is
// not noise in the data but the simulation's own. An optimiser that follows single evaluations
// (BOBYQA's quadratic model through its last few points) then stops wherever the rough part
// happens to dip, and the coarse scan's grid (a ninth of the range) decides the estimate: both
// FB35-D400 draws of 2026-11-30 ended on the same scan point, 13,889 N, for true frictions of
// 15.3 and 11.8 kN (docs/sim2real.md section 5, "Over fresh draws at D400"). A parabola fitted to
// many samples across the window averages the rough part out and keeps the trend; its vertex is
// the estimate where the samples have more than one local minimum (rough: a smooth objective with
// one optimum in the window has one) and the vertex lies inside the window, and an optimiser
// refines from it otherwise (the machine-alone runs, a trend that falls on beyond the window).
// The samples' scatter about the parabola does not tell the two apart: a smooth likelihood is a
// log of squared residuals, sharp at its optimum and flat away from it, and departs from a
// parabola by 0.03-0.30 of its rise (docs/sim2real.md section 3, "One parameter: the window's
// trend first").
#pragma once

#include <vector>

namespace talus::sim2real {

// the window of a one-parameter fit: from the scan point below the best to the one above (the
// range's bound at either end), and the points to sample in it besides the scan's own
struct FitWindow {
  double lo = 0.0, hi = 1.0;
  // ascending, none a scan point: strictly inside (lo, hi), and the bound itself at an end
  std::vector<double> new_points;
  // the smaller of the two sides' spacings between samples (the scan's near-zero points are
  // unevenly spaced): an optimiser refining in the window starts with half of it as its step
  double spacing = 0.0;
};

// the window around `best` (one of the ascending scan values `axis`, all in [0, 1]) with
// `per_side` points evenly spaced between it and each neighbour; at an end of the scan the
// neighbour is the range's bound (0 or 1), which is sampled too
FitWindow fit_window(const std::vector<double>& axis, double best, int per_side);

// the least-squares parabola y = a + b u + c u^2 through samples (u_k, y_k) in a window
struct LocalParabola {
  bool convex = false;        // c > 0: it has a minimum
  double vertex = 0.0;        // its minimum, clamped to the window [lo, hi] (convex only)
  bool clamped = false;       // its minimum lies outside the window: the trend falls on beyond
  double at_vertex = 0.0;     // its value there
  double rise = 0.0;          // its value at the window's farther end less at the vertex
  double residual_rms = 0.0;  // the samples' root-mean-square departure from it
  // the samples' scatter about the trend against the trend's own rise across the window: 0 for
  // a parabola sampled exactly, large where the rough part hides the trend
  double roughness() const;
};

// fits the parabola to at least three samples at distinct u (else throws Error); u scaled to the
// window first so the normal equations stay well conditioned
LocalParabola fit_parabola(const std::vector<double>& u, const std::vector<double>& y, double lo,
                           double hi);

// the number of local minima of samples (u_k, y_k) taken in the order of u: the places where y
// turns from falling to rising, equal neighbours skipped (a plateau is one place); an end counts
// when y rises away from it. The samples must be finite (else throws Error)
int local_minima(const std::vector<double>& u, const std::vector<double>& y);

// the likelihood's trend over a window's samples, and what the fit makes of it
struct WindowTrend {
  LocalParabola parabola;
  int local_minima = 0;
  // the vertex is the estimate: a trend with a minimum inside the window, under samples with
  // more than one local minimum (a rough likelihood); else an optimiser refines from the vertex
  // (or from the best sample where the trend has no minimum)
  bool rough() const;
};

// the trend of a window's finite samples (u_k, y_k), at least three at distinct u
WindowTrend window_trend(const std::vector<double>& u, const std::vector<double>& y,
                         const FitWindow& window);

}  // namespace talus::sim2real
