// Equivalent degrees of freedom and chi-square confidence intervals for the Allan family.
// Greenhall & Riley, "Uncertainty of stability variances based on finite differences",
// PTTI 2003 (EDF algorithm, eqs. 7-13, tables 1-3); NIST SP 1065 sec. 5.3 and Table 7 (TOTDEV).
#pragma once
#include <cstddef>
#include <utility>

namespace rig::analysis {

// d: 1 first difference, 2 Allan, 3 Hadamard. Requires alpha + 2d > 1 (clamped by callers).
// overlapping: OADEV/OHDEV/MDEV; modified: MDEV/TDEV. N: phase points.
double edf_greenhall(int alpha, int d, std::size_t m, std::size_t n_phase, bool overlapping, bool modified);

// TOTDEV: NIST SP 1065 Table 7, edf = b (N/m) - c for alpha 0, -1, -2 (T = N tau0), the
// simple approximations of Table 5 for the PM alphas; either at most OADEV's EDF times
// (N - 2) / (N - 2m) (at m = 1 TOTDEV is OADEV; edf.cpp says why).
double edf_totdev(std::size_t n_phase, std::size_t m, int alpha);
double edf_simple(std::size_t n_phase, std::size_t m, int alpha);

// (lo, hi) of a deviation for a two-sided interval at `confidence`:
// lo = dev sqrt(edf / chi2^-1((1+c)/2)), hi = dev sqrt(edf / chi2^-1((1-c)/2)) (SP 1065 eq. 45).
std::pair<double, double> chi2_bounds(double dev, double edf, double confidence);

}  // namespace rig::analysis
