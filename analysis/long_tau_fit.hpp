// Long-tau points for the noise-model fit (noise_model.hpp): Theo1 (NIST SP 1065 sec. 5.2.14,
// eq. 30; Howe & Tasset, "Theo1: characterization of very long-term frequency stability", EFTF
// 2004) at tau = T/2 and 0.75 T, past the OADEV grid's T/4 (Stable32's limit), with the
// expectation of each IEEE 952 term on the estimator actually computed, so that the fit puts the
// estimator's bias into the model instead of "correcting" the data.
//
// Theo1 at Theo1 factor m (even), tau = 0.75 m tau0, on N phase points:
//   Theo1(m) = 1 / (0.75 (N-m) (m tau0)^2) sum_{i<N-m} sum_{k=1}^{m/2}
//              [ (x_i - x_{i+k}) + (x_{i+m} - x_{i+m-k}) ]^2 / k        (k = m/2 - delta).
// It is computed on the phase sampled every `stride` points (X_j = x_{j stride}): that is Theo1
// of the record at tau0' = stride tau0, an exact statistic of the data (not an approximation of
// the full-rate Theo1), whose expectation per term is computed on exactly that grid. With at
// most kTheo1GridPoints phase points the two points cost ~1 ms whatever the record length.
//
// Each bracket is a combination sum c_a x(t_a) that annihilates constants and lines, so its
// expectation is E[(sum c_a x_a)^2] = -1/2 sum_ab c_a c_b D(t_a - t_b), D the term's phase
// structure function (up to a constant factor, which cancels in the ratio to the Allan
// variance computed the same way): white PM D = 2 [s != 0], white FM |s|, flicker FM
// -s^2 ln|s|, random-walk FM -|s|^3; the ramp (x = t^2, deterministic) the bracket itself,
// 2 k (m - k) whatever i.
#pragma once
#include <array>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "analysis/allan.hpp"

namespace rig::analysis {

struct LongTauFitPoint {
  std::string estimator = "theo1";
  std::size_t m = 0;        // Theo1 factor in samples of the record (j stride, j even); tau = 0.75 m tau0
  double tau_s = 0;         // 0.75 m tau0
  double frac = 0;          // tau / T the point was placed at (its row in the measured EDF tables)
  double var = 0;           // the statistic (a variance, the unit^2 of the record)
  std::size_t stride = 1;   // phase every stride-th point
  std::size_t starts = 0;   // subsequence starts summed (N' - j on the grid)
  std::size_t n_phase = 0;  // phase points of the record the statistic spans (stride K + 1)
  // E[statistic] / AVAR(tau) per IEEE 952 term Q, N, B, K, R on exactly this grid (SP 1065's
  // Theo1 is unbiased against AVAR for white FM only; the others have a bias that depends on
  // tau/T): from the terms' structure functions, the ramp's deterministically.
  std::array<double, 5> factor{};
  // The ramp's scatter: Theo1 of ramp + noise is E_R + E_noise + C, C the cross term
  // A sum_{i,k} 2 R_k e_{i,k} / k (R_k the ramp's brackets, e the noise's, A the normalisation).
  // var(C) = sum_k ramp_cross[k] E_R E_k over Q, N, B, K (E the terms' Theo1 expectations),
  // exact for white PM, white FM and random-walk FM as a linear functional of the phase;
  // flicker FM the geometric mean of white and random-walk FM's (flicker lies between them).
  std::array<double, 4> ramp_cross{};
  double edf = 0;  // the model's EDF of the point, filled in by the fit (0 until then)
};

// Phase points of the decimated grid at most (stride = ceil((N-1)/kTheo1GridPoints)).
inline constexpr std::size_t kTheo1GridPoints = 2048;
// Where the points go, as tau / T: one octave past OADEV's T/4, and Theo1's longest tau.
inline constexpr std::array<double, 2> kTheo1Fractions{0.5, 0.75};

// The phase every `stride` points of a record (frequency: block sums, the first value's
// frequency removed; phase: the line through its ends removed). Empty on a non-finite value or
// a read failure.
std::vector<double> decimated_phase(const ChunkSource& src, DataKind kind, double rate_hz, std::size_t stride);

// The Theo1 points at kTheo1Fractions of a record of frequency (or phase) values, read once
// sequentially from `src`. Empty when the record has fewer than 32 phase points.
std::vector<LongTauFitPoint> theo1_fit_points(const ChunkSource& src, DataKind kind, double rate_hz);
std::vector<LongTauFitPoint> theo1_fit_points(std::span<const double> data, DataKind kind, double rate_hz);

// E[Theo1] / AVAR(0.75 j stride) per term on a grid of K+1 points `stride` apart, Theo1 factor j.
std::array<double, 5> theo1_factors(std::size_t K, std::size_t j, std::size_t stride);
// LongTauFitPoint::ramp_cross on that grid.
std::array<double, 4> theo1_ramp_cross(std::size_t K, std::size_t j, std::size_t stride);

// The log-scale EDF of a Theo1 point for term 0..3 (Q, N, B, K) at tau/T = frac, measured by
// simulation (tests/analysis/test_noise_coverage.cpp `LongTauFit.*`, the generator of
// injected_noise.hpp; docs/analysis.md "Theo1 points"): var(ln s) = 2 / nu_var and
// E[ln(s/E s)] = digamma(nu_mean/2) - ln(nu_mean/2). SP 1065's Theo1 EDF (edf_theo1) is not used
// here: its random-walk formula is below 1 at T/2 and negative past 0.63 T, and the fit's log
// scale needs the measured moments anyway (as the TOTVAR point did, branch `longtau`).
double theo1_term_edf_var(int term, double frac);
double theo1_term_edf_mean(int term, double frac);
// Correlation of ln Theo1(frac T) with ln OADEV(T/4) for term 0..3, measured likewise; with the
// OADEV points before T/4 the chain continues by kOctaveCorr (noise_model.cpp).
double theo1_corr_oadev(int term, double frac);
// Correlation of ln Theo1(T/2) with ln Theo1(0.75 T) for term 0..3, measured likewise.
double theo1_corr_pair(int term);
// The factor on the ramp's exact cross-term variance for the log scale (measured; see the .cpp).
double theo1_ramp_cross_log_scale(double frac);
// The correlation of the ramp's cross term (measured where it dominates) with ln OADEV^2 at T/4,
// and between the two Theo1 points.
double theo1_ramp_corr_oadev(double frac);
double theo1_ramp_corr_pair();

}  // namespace rig::analysis
