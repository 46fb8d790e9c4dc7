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
//      model's EDF and covariance, the widest non-negative model, terms reported by AICc or an
//      interval excluding 0), with 68 % bounds or upper limits.
#pragma once
#include <array>
#include <cmath>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "analysis/allan.hpp"
#include "analysis/drift.hpp"
#include "analysis/noise_model.hpp"

namespace rig::analysis {

struct Term {
  std::optional<double> value;
  std::optional<double> lo, hi;
  std::string unit;
  std::string reason;  // why value is null, or which method produced it; numbers in `unit`
  // A term the model leaves out (null, `hi` its upper limit): `reason` without its clause
  // "upper limit X <= hi unit", so a reader quoting the term in other units (the passport's per
  // hour) states the limit from `hi` in its own unit. Empty when `reason` carries no such clause.
  std::string reason_without_limit;
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
  double chi2_per_dof = 0;  // the model's GLS chi-square per dof over the points fitted (noise_model.hpp)
  double model_error = 0;   // Birge model error delta (0 unless no tau range passed the goodness-of-fit test)
  // per term Q, N, B, K, R (0 when not in the fit): its largest share of the model sigma^2 over
  // the measured taus, and its fitted squared coefficient over the coefficient's sd
  std::array<double, 5> share{}, z{};
};

// sigma_flat = sqrt(2 ln2 / pi) B = 0.6643 B (IEEE 952 Annex C), to double precision
// (sqrt(2 ln2 / pi) = 0.664282470267960019...). The first version carried 0.66428001915095,
// 3.7e-6 below it; B by the paper's method moved by +3.7e-6 (relative) when it was corrected.
inline constexpr double kBiasFactor = 0.66428247026796002;

// The Allan deviation each noise term alone contributes at tau (IEEE Std 952-1997 Annex C,
// Table C.1; docs/analysis.md). Coefficients in the input unit g with tau in seconds.
// The model's sigma^2(tau) is the sum of their squares.
//   quantisation          sigma_Q(tau) = sqrt(3) Q / tau        slope -1
inline double sigma_q(double q, double tau_s) { return std::sqrt(3.0) * q / tau_s; }
//   velocity random walk  sigma_N(tau) = N / sqrt(tau)          slope -1/2
inline double sigma_n(double n, double tau_s) { return n / std::sqrt(tau_s); }
//   bias instability      sigma_B      = sqrt(2 ln2 / pi) B     flat (0.664 B)
inline double sigma_b(double b, double /*tau_s*/) { return kBiasFactor * b; }
//   rate random walk      sigma_K(tau) = K sqrt(tau / 3)        slope +1/2
inline double sigma_k(double k, double tau_s) { return k * std::sqrt(tau_s / 3.0); }
//   rate ramp             sigma_R(tau) = R tau / sqrt(2)        slope +1
inline double sigma_r(double r, double tau_s) { return r * tau_s / std::sqrt(2.0); }

// The fitted curves on the Allan taus, for drawing (the report and `rig analyze --svg` only
// draw them): each identified term's sigma_X(tau), the sum of the weighted fit's identified
// terms sqrt(sum sigma_X^2), and the paper's polynomial 10^(sum_k coef[k] (log10 tau)^k).
// A term without a value has an empty curve.
struct FittedCurves {
  std::vector<double> tau_s;
  std::vector<double> Q, N, B, K, R;  // the rig's values (B by the paper's method)
  std::vector<double> lsq_fit;        // the weighted fit's identified terms together
  std::vector<double> paper_poly;     // empty when the paper's fit failed
};

// R read from the record's drift (noise_terms' `drift`; docs/analysis.md).
struct DriftReading {
  double slope = 0;     // g/s, signed: the least-squares slope of the record
  double sd = 0;        // g/s: the noise's scatter of that slope, from the model's N, B, K (and Q)
  double edf = 0;       // of sd^2 (Welch-Satterthwaite over the model terms'; inf when none is estimated)
  double quantile = 0;  // Student's t at `edf` for the bounds' confidence (NoiseTerms::confidence)
};

struct NoiseTerms {
  Term Q, N, B, K, R;  // the rig's values: B by the paper's method, Q N K by the model, R by the
                       // record's drift when noise_terms() has it (else by the model)
  std::optional<DriftReading> drift;  // set when R was read from the drift
  std::optional<double> tau_cp_s;  // the flat segment's middle (B = sigma(tau_cp) / 0.664)
  std::optional<double> sigma_cp;
  PaperFit paper;
  WlsFit wls;          // the model fit (noise_model.hpp) in the shape of the former weighted fit
  NoiseModelFit model;  // the one model: every term the data supports, with bounds or upper limits
  // How B was read (B above): "flat_segment" (the paper's, tau_cp the middle of the segment
  // flat_tau_from_s..flat_tau_to_s), "polynomial_minimum" (no flat segment: the quartic's
  // interior minimum), "least_squares" (neither: the model's B), or "" (no B). The paper
  // method's bounds are the chi-square bounds of sigma(tau_cp) at the EDF of the polynomial's
  // value there (b_edf: from every point it reads, under the model's covariance; without a model
  // the nearest Allan point's EDF), over 0.664: its scatter, not its bias. Every term
  // adds to sigma^2(tau_cp), so that interval bounds B from above only; its lower end is
  // lowered to the model's B lower bound (0 when the model has no B) where that is lower.
  std::string b_method;
  std::optional<double> flat_tau_from_s, flat_tau_to_s, b_edf;
  FittedCurves curves;  // on the taus of the Allan points the terms were fitted to
  double confidence = kOneSigma;  // of every bound and upper limit above
};

// The curves of `t` on `taus` (noise_terms() fills NoiseTerms::curves with this).
FittedCurves fitted_curves(const NoiseTerms& t, std::span<const double> taus);

// The shortest record from which the method determines the rate ramp R (docs/method.md: > 50 h);
// a shorter record's R (still fitted: the model has R as a candidate on every record) says so.
inline constexpr double kRMinRecordS = 50 * 3600.0;

// oadev: the overlapping Allan deviation points (edf used as weights; 0 = unweighted).
// r_min_record_s: the record length a profile requires for R; a shorter record's R notes it.
// drift: the record's least-squares drift (drift.hpp); with it R is read from the drift, its
// scatter from the model's other terms (the model's own R stays in `wls`); without it (Allan
// points alone) R is the model's.
// confidence: of every bound and upper limit (default one sigma); the values, and which terms are
// reported, are the method's and do not depend on it.
NoiseTerms noise_terms(std::span<const DevPoint> oadev, double record_length_s,
                       double r_min_record_s = kRMinRecordS, const std::optional<Drift>& drift = std::nullopt,
                       double confidence = kOneSigma);

// The terms of a record with no noise to fit (a constant record, a straight phase line: every
// Allan deviation 0, or the rounding of the values): every term null with `why` as its reason,
// and the fits' reasons too. noise_terms() returns it when every OADEV point is 0; a caller that
// knows the values' rounding (rig analyze) calls it for deviations at that level too.
NoiseTerms no_noise_terms(const std::string& why, double confidence = kOneSigma);

// Passport units (docs/method.md quotes the terms per hour): 1 h = 3600 s, so a coefficient in
// g*s^a is 3600^-a of itself in g*h^a. Written as products with the same factors the passport
// values are scaled by (procedures/acceptance), so both carry the same bits.
inline constexpr double kQToHour = 1.0 / 3600.0, kNToHour = 1.0 / 60.0, kKToHour = 60.0, kRToHour = 3600.0;
inline double q_per_hour(double q_g_s) { return q_g_s * kQToHour; }       // g*s -> g*h
inline double n_per_hour(double n_g_rts) { return n_g_rts * kNToHour; }   // g*s^0.5 -> g*h^0.5
inline double k_per_hour(double k_g_prts) { return k_g_prts * kKToHour; } // g/s^0.5 -> g/h^0.5
inline double r_per_hour(double r_g_ps) { return r_g_ps * kRToHour; }     // g/s -> g/h

}  // namespace rig::analysis
