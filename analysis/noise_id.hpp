// Per-tau power-law noise identification as Stable32 does it (Riley, Handbook of Frequency
// Stability Analysis, NIST SP 1065 sec. 5.6): the lag-1 autocorrelation method (Riley &
// Greenhall 2004) when at least 30 averaged points exist, else the B1 ratio with R(n)
// to tell white from flicker PM. alpha is the exponent of S_y(f) = h_alpha f^alpha.
// The details that NIST SP 1065 leaves open were fixed against Stable32's printed alpha
// column (tests/data/allan-reference, every table; see docs/analysis.md).
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>

namespace rig::analysis {

struct NoiseId {
  int alpha = 0;
  double alpha_f = 0;  // non-integer estimate (ACF method), for diagnostics
  int d = 0;           // differences taken (ACF method)
  double rho = 0;
  bool acf = true;     // false: B1/R(n) rules
};

// Lag-1 autocorrelation r1 = sum (x_n - mean)(x_{n+1} - mean) / sum (x_n - mean)^2.
double lag1_acf(std::span<const double> x);

// ACF method on an m-averaged frequency (phase = false) or m-decimated phase (phase = true)
// series of >= 30 points, used as is (no detrending); dmax = 2 for the Allan and modified
// variances, 3 for the Hadamard ones.
NoiseId acf_noise_id(std::span<const double> series, bool phase, int dmax);

// Expected B1 = (standard variance)/(Allan variance) for n averaged points and tau exponent mu.
double b1_theory(double n, int mu);
// Expected R(n) = Mod AVAR / AVAR at averaging factor m for alpha = 2 (white PM) and 1 (flicker PM).
double rn_theory(std::size_t m, int alpha);

// Observed B1 ratio: sample variance (n - 1) of z over its non-overlapped Allan variance.
double b1_ratio(std::span<const double> z);

// B1 -> mu (tau exponent of the Allan variance, 2 .. -2) with n as N of B1(N, mu); the
// boundaries are the geometric means of neighbouring expected values.
int b1_mu(double b1, double n);

// One tau with fewer than 30 averages, as Stable32 identifies it.
struct B1Rules {
  std::size_t m = 1;               // averaging factor
  std::uint64_t n_terms = 0;       // the deviation's term count, Stable32's N of B1(N, mu)
  std::size_t max_factor = 0;      // Stable32's largest factor for the deviation (allan.hpp)
  bool hadamard = false;           // HDEV/OHDEV: B1 of first differences splits RW/FW/RR FM
  std::optional<int> previous;     // alpha identified at the previous (shorter) tau, if any
};

// z: the m-averaged fractional frequencies. mod_avar: Mod AVAR at m, given only for MDEV/TDEV
// (the one family whose R(n) Stable32 evaluates; < 0 = not available). Past max_factor / 2
// the previous alpha is repeated.
NoiseId b1_rn_noise_id(std::span<const double> z, const B1Rules& r, const std::function<double()>& mod_avar);

}  // namespace rig::analysis
