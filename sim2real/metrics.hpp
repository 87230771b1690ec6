// Sim-to-real error measures of Aoshima & Servin (reference/wheel-loader-sim2real-gap.tex §3.1, §6)
// and SPEC §4. Everything is double precision and free of state; see docs/metrics.md for the
// choices the paper leaves open (N, L_norm, which measure applies to which channel).
#pragma once
#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace talus::sim2real {

// a trajectory: one row per sample, one column per spatial dimension (like a numpy (M, D) array)
using Trajectory = Eigen::MatrixXd;

// max_n |f_n|: the paper's default normaliser f_norm ("maximum absolute value", §3.1)
double max_abs(const std::vector<double>& f);

// normalised mean absolute error E_f = (1/N) Σ_n |f_n − f̂_n| / f_norm over N = f.size() samples.
// f and reference must have equal, non-zero length; f_norm must be positive and finite.
double normalised_mae(const std::vector<double>& f, const std::vector<double>& reference,
                      double f_norm);
// the same with f_norm = max |f̂| of the reference
double normalised_mae(const std::vector<double>& f, const std::vector<double>& reference);

// normalised mean Euclidean error E = (1/N) Σ_n ‖x_n − x̂_n‖₂ / L_norm over N = rows samples.
double normalised_mee(const Trajectory& x, const Trajectory& reference, double l_norm);

// dynamic time warping distance exactly as similaritymeasures.dtw (metric 'euclidean'):
// c[i,j] = ‖a_i − b_j‖₂ (not squared), d[0,0] = c[0,0], first row and column accumulate,
// d[i,j] = c[i,j] + min(d[i−1,j], d[i,j−1], d[i−1,j−1]); the distance is d[last,last].
// a and b may have different numbers of rows but must have the same number of columns.
// Memory O(b.rows()): only two rows of the cumulative matrix are kept.
double dtw_distance(const Trajectory& a, const Trajectory& b);

// normalised DTW error E_DTW = d / (N L_norm) (paper eq. 3); the caller passes N, which talus
// takes to be the number of reference (measured) samples in the compared window
double normalised_dtw(double distance, std::size_t n, double l_norm);

// L_norm used by talus: the diagonal of the axis-aligned bounding box of the reference
// trajectory, i.e. its spatial extent (translation invariant, unlike max ‖x̂‖, whose value
// depends on where the origin is; the paper does not state its L_norm)
double trajectory_extent(const Trajectory& reference);

// relative error (q − q̂)/q̂ of a scalar such as loaded mass or work; q̂ must be non-zero
double relative_error(double value, double reference);

// E_M, the loaded mass's relative error. A measured cycle may bring the bucket back empty (a dig
// that fails to penetrate: real field data has them); its relative error is then undefined, NaN,
// unless the simulated bucket is empty too (0: they agree). Tables print an undefined column as
// n/a and the means skip it (paper_mean, sim2real::mean_row); a negative or non-finite mass is
// refused (InputError)
double loaded_mass_error(double simulated_kg, double measured_kg);

// the paper's seven table columns in their order
struct ErrorColumns {
  double e_x = 0.0;   // bucket-tip trajectory, normalised DTW
  double e_v = 0.0;   // drive speed, normalised MAE
  double e_tr = 0.0;  // traction force, normalised MAE
  double e_l = 0.0;   // lift cylinder force, normalised MAE
  double e_t = 0.0;   // tilt cylinder force, normalised MAE
  double e_m = 0.0;   // loaded mass, relative error (signed)
  double e_w = 0.0;   // work, relative error (signed)

  std::array<double, 7> as_array() const { return {e_x, e_v, e_tr, e_l, e_t, e_m, e_w}; }
};

// the paper's "mean" column: the mean of the absolute values of the seven columns (of those
// defined: an undefined E_M, NaN, is skipped; NaN when none is defined)
double paper_mean(const ErrorColumns& e);
double paper_mean(const std::array<double, 7>& columns);

}  // namespace talus::sim2real
