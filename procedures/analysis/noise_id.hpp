// Per-tau power-law noise identification as Stable32 does it (Riley, Handbook of Frequency
// Stability Analysis, NIST SP 1065 sec. 5.6): the lag-1 autocorrelation method (Riley &
// Greenhall 2004) when at least 30 averaged points exist, else the B1 ratio with R(n)
// to tell white from flicker PM. alpha is the exponent of S_y(f) = h_alpha f^alpha.
#pragma once
#include <cstddef>
#include <span>
#include <vector>

namespace rig::analysis {

struct NoiseId {
  int alpha = 0;
  double alpha_f = 0;  // non-integer estimate (ACF method), for diagnostics
  int d = 0;           // differences taken (ACF method)
  double rho = 0;
  bool acf = true;     // false: B1/R(n) fallback
};

// Lag-1 autocorrelation r1 = sum (x_n - mean)(x_{n+1} - mean) / sum (x_n - mean)^2.
double lag1_acf(std::span<const double> x);

// ACF method on an already averaged (frequency) or decimated (phase) series of >= 30 points.
// Frequency series are detrended linearly, phase series quadratically; dmax = 2 for the Allan
// and modified variances, 3 for the Hadamard ones.
NoiseId acf_noise_id(std::span<const double> series, bool phase, int dmax);

// Expected B1 = (standard variance)/(Allan variance) for n averaged points and tau exponent mu.
double b1_theory(double n, int mu);
// Expected R(n) = Mod AVAR / AVAR at averaging factor m for alpha = 2 (white PM) and 1 (flicker PM).
double rn_theory(std::size_t m, int alpha);

// B1/R(n) identification: b1 observed with n averaged points, rn observed (< 0 when not
// available: white and flicker PM are then not told apart and 1 is reported).
NoiseId b1_rn_noise_id(double b1, double n, double rn, std::size_t m);

}  // namespace rig::analysis
