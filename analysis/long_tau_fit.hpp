// Long-tau points for the noise-model fit (noise_model.hpp): the total variance TOTVAR (NIST
// SP 1065 sec. 5.2.11, eq. 25) at tau = T/2, past the OADEV grid's T/4 (Stable32's limit), with
// the expectation of each IEEE 952 term on the estimator actually computed, so that the fit puts
// the estimator's bias into the model instead of "correcting" the data.
//
// TOTVAR extends the phase x_1..x_N by reflection at both ends (x*_{1-j} = 2 x_1 - x_{1+j},
// x*_{N+j} = 2 x_N - x_{N-j}) and averages the squared second differences over every centre:
//   Totvar(tau) = 1 / (2 tau^2 (N-2)) sum_{i=2}^{N-1} (x*_{i-m} - 2 x*_i + x*_{i+m})^2,  m <= (N-1)/2.
// At tau = T/2 every centre reaches past an end, which is why TOTVAR has more degrees of
// freedom there than any Allan variance can (SP 1065 Table 7: EDF = b T/tau - c).
//
// Cost: one pass over the record (block sums of the frequency every `stride` points: the phase
// on a coarse grid), then ~1000 centres. At tau >= T/4 the second differences of neighbouring
// centres share almost all their phase points; summing every stride-th centre (stride = m/512)
// loses almost nothing (docs/analysis.md "Long-tau points").
#pragma once
#include <array>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "analysis/allan.hpp"

namespace rig::analysis {

struct LongTauFitPoint {
  std::string estimator = "totvar";
  std::size_t m = 0;        // averaging factor (a multiple of stride)
  double tau_s = 0;         // m tau0
  double var = 0;           // the statistic (a variance, the unit^2 of the record)
  std::size_t stride = 1;   // centres and phase points every stride-th phase point
  std::size_t centres = 0;  // second differences summed
  std::size_t n_phase = 0;  // phase points of the record the statistic spans (stride * K + 1)
  // E[statistic] / AVAR(tau) per IEEE 952 term Q, N, B, K, R on exactly these centres: white PM
  // (Q), white FM (N), random-walk FM (K) from their phase covariances, the ramp R from a
  // quadratic phase (deterministic) through the same estimator; flicker FM (B) by SP 1065 sec.
  // 5.2.11, 1 - tau / (3 ln2 T).
  std::array<double, 5> factor{};
  // The ramp's scatter: TOTVAR of ramp + noise is E_R + E_noise + C, C the cross term (1/(tau^2
  // (centres))) sum_k D_R(k) e(k) (D_R the ramp's second differences, smaller at the reflected
  // edges, e the noise's). var(C) = sum_k ramp_cross[k] E_R E_k over Q, N, B, K (E the terms'
  // TOTVAR expectations), computed exactly for white PM, white FM and random-walk FM as a linear
  // functional of the phase (totvar_ramp_cross); flicker FM the geometric mean of white and
  // random-walk FM's (an approximation: flicker lies between them).
  std::array<double, 4> ramp_cross{};
  double edf = 0;  // the model's EDF of the point, filled in by the fit (0 until then)
};

// Centres kept per averaging factor at most (the stride is m / kCentresPerM, at least 1).
inline constexpr std::size_t kTotvarCentresPerM = 512;

// The TOTVAR point at m = (N-1)/2 (tau = T/2, TOTDEV's largest) of a record of frequency (or
// phase) values, read once sequentially from `src`. Empty when the record has fewer than 16
// phase points (too short for the model fit's long tau to mean anything) or a value is not finite.
std::vector<LongTauFitPoint> totvar_fit_points(const ChunkSource& src, DataKind kind, double rate_hz);
std::vector<LongTauFitPoint> totvar_fit_points(std::span<const double> data, DataKind kind, double rate_hz);

// TOTVAR of the phase X sampled every `stride` points (X[k] = x_{k stride}, tau0 apart
// originally), at m = j stride, summed over the interior centres k = 1..K-1 (K = X.size() - 1);
// with stride 1 exactly SP 1065 eq. 25.
double totvar_on_grid(std::span<const double> X, std::size_t j, std::size_t stride, double tau0);

// E[TOTVAR] / AVAR for each IEEE 952 term on that grid (LongTauFitPoint::factor).
std::array<double, 5> totvar_factors(std::size_t K, std::size_t j, std::size_t stride);
// LongTauFitPoint::ramp_cross on that grid.
std::array<double, 4> totvar_ramp_cross(std::size_t K, std::size_t j, std::size_t stride);

// The per-term EDF of a TOTVAR point (SP 1065 Table 7, edf = b N/m - c: white FM (1.50, 0),
// flicker FM (1.17, 0.22), random walk FM (0.93, 0.36); white PM has no entry and takes white
// FM's, which understates it) times scale[term], for the model's mixture EDF (noise_model.cpp).
//
// The fit works on ln s, whose variance it takes as 2/nu and whose mean as ln E[s] +
// E[ln(chi2_nu/nu)]. At T/2 TOTVAR is not chi-square with Table 7's EDF on that scale: simulated
// (the generator of tests/analysis, 1000 records of 4096, 300 of 40000 and 150 of 360000 points
// per noise type, 2026-11-24), var(ln s) is 0.60-0.64 (white FM), 1.02-1.09 (flicker FM),
// 1.35-1.58 (random walk FM) against 2/nu = 0.667, 0.943, 1.333, and the mean of ln(s/E[s])
// -0.30, -0.44, -0.62 (pooled; -0.54..-0.66 per length) against -0.37, -0.54, -0.80. So the
// variance takes nu x kTotvarLnVarScale (0.87 flicker, 0.85 random walk; white kept at 1,
// slightly conservative) and the log bias nu x kTotvarLnMeanScale (the EDF whose
// E[ln(chi2_nu/nu)] is the measured mean: 1.2, 1.27, 1.23). Without them the TOTVAR point
// pulled the curve 1.2x up where random walk dominates and claimed 15-20 % too little scatter.
inline constexpr std::array<double, 4> kTotvarLnVarScale{1.0, 1.0, 0.87, 0.85};
inline constexpr std::array<double, 4> kTotvarLnMeanScale{1.2, 1.2, 1.27, 1.23};
double totvar_term_edf(int term, std::size_t n_phase, std::size_t m, const std::array<double, 4>& scale = {1, 1, 1, 1});

}  // namespace rig::analysis
