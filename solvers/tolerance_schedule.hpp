// When a step's sweeps look at their residual, with a tolerance (DemSettings::tolerance, issue 13).
//
// A look costs about one sweep: row_residual is a pass over every row, and its sum a host wait
// (bench/RESULTS.md 2026-11-29 "Where the looks fall": at HD27-D100 5.8 ms a look, 5.1 ms a
// sweep). Looking every ten sweeps spent a step's seven looks at D100 and overshot the first sweep
// below the tolerance by about half the interval. Measured on every sweep of HD27-D200's steps
// (docs/dem.md "Where the looks fall"), the residual falls as a power of the sweeps, r ~ A n^-p
// with p near 1, not geometrically. So: the first two looks ten sweeps apart, and each later one
// where the power law through the last two looks reaches the tolerance, at least one sweep and at
// most kMaxLookStride sweeps on (the first sweep past the crossing); where the residual did not
// fall between two looks, ten sweeps on. The stopping rule is unchanged (the sweeps end at the
// first look below the tolerance); only where the looks fall is new.
#pragma once

namespace talus {

// sweeps before the first look and between the first two (and after a look that did not fall)
inline constexpr int kFirstLookInterval = 10;
// the most sweeps the power law may put between two looks: one bad extrapolation runs at most
// this far past the crossing (HD27-D200 replayed: 20 costs 3.6 sweeps a pass more than 40 in
// looks, 80 saves 0.8 more; docs/dem.md "Where the looks fall")
inline constexpr int kMaxLookStride = 40;

class ToleranceSchedule {
 public:
  // `tolerance` [m/s] > 0
  explicit ToleranceSchedule(double tolerance);

  // the sweeps (counted from the first of the step, or of the coupled step's pass) after which
  // to look next
  int next_look() const { return next_; }

  // records the RMS residual [m/s] seen after `sweeps` sweeps and places the next look; true when
  // it is below the tolerance (the sweeps end)
  bool look(int sweeps, double residual);

 private:
  double tolerance_;
  int next_ = kFirstLookInterval;
  // the last look: sweeps and residual (sweeps 0: none yet)
  int last_sweeps_ = 0;
  double last_residual_ = 0.0;
};

}  // namespace talus
