// IEEE Std 952 / 1293 noise terms of an accelerometer from its overlapping Allan deviation
// (units: the input unit, g, with tau in SECONDS; the *_per_hour helpers convert to the
// passport's g*h, g*h^0.5, g/h^0.5, g/h).
//
//   sigma^2(tau) = 3 Q^2/tau^2 + N^2/tau + (2 ln2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2
//
// Two methods are reported side by side (docs/method.md, procedure C):
//  (a) the paper's: a 4th-degree least-squares polynomial of log10 sigma over log10 tau, its
//      inflection points, the segments between them with their slopes, sigma at each segment's
//      middle tau, and B = sigma(tau_cp) / 0.664 on the flat one;
//  (b) one model of all five terms (noise_model.hpp: GLS on the octave Allan points with the
//      model's EDF and covariance, AICc selection), with 68 % bounds or upper limits.
#pragma once
#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "analysis/allan.hpp"
#include "analysis/noise_model.hpp"

namespace rig::analysis {

struct Term {
  std::optional<double> value;
  std::optional<double> lo, hi;
  std::string unit;
  std::string reason;  // why value is null, or which method produced it
};

// One segment of the paper's polynomial between inflection points.
struct Segment {
  double tau_lo_s = 0, tau_hi_s = 0;
  double slope = 0;       // d log sigma / d log tau at the middle
  double tau_mid_s = 0;   // geometric middle (the paper's tau_cp for the flat one)
  double sigma_mid = 0;   // polynomial sigma at tau_mid
  std::string term;       // nearest IEEE 952 slope: Q (-1), N (-1/2), B (0), K (+1/2), R (+1)
  double term_value = 0;  // that term from sigma_mid by its slope relation
};

struct PaperFit {
  bool ok = false;
  std::string reason;
  int degree = 4;
  std::array<double, 5> coef{};  // log10 sigma = sum_k coef[k] (log10 tau)^k
  std::vector<double> inflection_tau_s;
  std::vector<Segment> segments;
};

struct WlsFit {
  bool ok = false;
  std::string reason;
  Term Q, N, B, K, R;
  std::size_t points = 0;
  double chi2_per_dof = 0;  // of the EDF weights alone: how far the five-term model is from the curve
  double model_error = 0;   // relative model error delta added to each point (0: EDF weights only)
  // per term Q, N, B, K, R (0 when not in the fit): its largest share of the model sigma^2 over
  // the measured taus, and its fitted squared coefficient over the coefficient's sd
  std::array<double, 5> share{}, z{};
};

struct NoiseTerms {
  Term Q, N, B, K, R;  // the rig's values: B by the paper's method, Q N K R by the model
  std::optional<double> tau_cp_s;  // the flat segment's middle (B = sigma(tau_cp) / 0.664)
  std::optional<double> sigma_cp;
  PaperFit paper;
  WlsFit wls;          // the model fit (noise_model.hpp) in the shape of the former weighted fit
  NoiseModelFit model;  // the one model: every term the data supports (AICc), with bounds or upper limits
  // How B was read (B above): "flat_segment" (the paper's, tau_cp the middle of the segment
  // flat_tau_from_s..flat_tau_to_s), "polynomial_minimum" (no flat segment: the quartic's
  // interior minimum), "least_squares" (neither: the model's B), or "" (no B). The paper
  // method's bounds are the chi-square bounds of sigma(tau_cp) at the EDF the model implies at
  // the Allan point nearest tau_cp (b_edf), over 0.664: its scatter, not its bias.
  std::string b_method;
  std::optional<double> flat_tau_from_s, flat_tau_to_s, b_edf;
};

// sigma_flat = sqrt(2 ln2 / pi) B = 0.6643 B (IEEE 952 Annex C).
inline constexpr double kBiasFactor = 0.66428001915095;

// The shortest record from which the method determines the rate ramp R (docs/method.md: > 50 h);
// a shorter record's R (still fitted: the model has R as a candidate on every record) says so.
inline constexpr double kRMinRecordS = 50 * 3600.0;

// oadev: the overlapping Allan deviation points (edf used as weights; 0 = unweighted).
// r_min_record_s: the record length a profile requires for R; a shorter record's R notes it.
NoiseTerms noise_terms(std::span<const DevPoint> oadev, double record_length_s,
                       double r_min_record_s = kRMinRecordS);

// Passport units.
inline double q_per_hour(double q_g_s) { return q_g_s / 3600.0; }       // g*s -> g*h
inline double n_per_hour(double n_g_rts) { return n_g_rts / 60.0; }     // g*s^0.5 -> g*h^0.5
inline double k_per_hour(double k_g_prts) { return k_g_prts * 60.0; }   // g/s^0.5 -> g/h^0.5
inline double r_per_hour(double r_g_ps) { return r_g_ps * 3600.0; }     // g/s -> g/h

}  // namespace rig::analysis
