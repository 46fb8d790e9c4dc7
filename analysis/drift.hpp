// The record's drift: the least-squares slope of the output (frequency data y, g) against time,
// and the scatter each IEEE Std 952 noise term gives it. The rate ramp R of IEEE 952 (Annex C:
// sigma_R(tau) = R tau / sqrt 2) is this slope when it is deterministic; a random walk K also
// rises over a record, and its realisation's slope is what limits how well one record
// determines R (docs/analysis.md "R from the record's drift").
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <span>

namespace rig::analysis {

// Neumaier's compensated sum (Kahan-Babuska): the drift's sums cancel almost entirely when the
// record has no drift, so their rounding must stay at the terms' level, not the total's.
struct CompensatedSum {
  double sum = 0, err = 0;
  void add(double x) {
    const double t = sum + x;
    err += std::abs(sum) >= std::abs(x) ? (sum - t) + x : (x - t) + sum;
    sum = t;
  }
  double value() const { return sum + err; }
};

struct Drift {
  double slope = 0;       // g/s: sum_k c_k y_k / (tau0 sum_k c_k^2), c_k = k - (n - 1)/2
  std::uint64_t n = 0;    // frequency values the slope is fitted to
  double tau0 = 0;        // s
  bool ok() const { return n >= 3 && tau0 > 0; }
  double length_s() const { return static_cast<double>(n) * tau0; }
};

// Directly from the frequency values (compensated sums: the slope to rounding whatever n).
Drift least_squares_drift(std::span<const double> y, double rate_hz);

// From a phase built as P_0 = 0, P_{j+1} = P_j + (y_j - c) (any constant c: sum_k c_k = 0 removes
// it), given its last point P_n and the sum of P_0..P_n. Summation by parts:
//   sum_k c_k (y_k - c) = (n + 1)/2 P_n - sum_{j=0}^{n} P_j,   sum_k c_k^2 = n (n^2 - 1)/12.
// The analysis engine keeps these two numbers of its pass (StreamOptions::drift), so the drift of a
// mapped or streamed record costs no pass of its own.
Drift drift_from_phase_sums(std::uint64_t n, double p_last, double p_sum, double tau0);

// The variance of the slope of a record of length T = n tau0 that holds only noise with the IEEE
// 952 coefficients q = {Q, N, B, K} (g s, g s^0.5, g, g/s^0.5), each term's share (white FM and
// the random walk exact for the discrete record to O(1/n); flicker for a 1/f spectrum to 0 Hz):
//   white phase Q (sigma_x = Q):    72 Q^2 / T^4             (the phase's two end points)
//   white rate N (h0 = 2 N^2):      12 N^2 / T^3
//   flicker B (h-1 = B^2 / pi):      9 B^2 / (pi T^2)        (integral |H(f)|^2 h-1/f df, = 1/16)
//   random walk K (h-2 = K^2/2pi^2): 6 K^2 / (5 T)            (E[b^2] of K W(t) on [0, T])
// (h_alpha from each term's Allan variance: AVAR = h0/(2 tau), 2 ln2 h-1, (2 pi^2/3) h-2 tau,
// IEEE Std 1139 / NIST SP 1065; H(f) the transfer function of the least-squares slope).
// Returned per term, so a caller can weigh each by what it knows of it.
std::array<double, 4> drift_variance_terms(const std::array<double, 4>& q, const Drift& d);

}  // namespace rig::analysis
