// One model for the IEEE Std 952 noise terms of an accelerometer, every term the data supports.
//
//   sigma^2(tau) = theta_Q 3/tau^2 + theta_N /tau + theta_B (2 ln2/pi) + theta_K tau/3 + theta_R tau^2/2,
//   theta = (Q^2, N^2, B^2, K^2, R^2) >= 0                                   (IEEE 952 Annex C)
//
// Fitted to the overlapping Allan variances at the octave averaging factors (m = 1, 2, 4, ...:
// the least correlated subset, Schlossberger & Howe, NIST) by generalized least squares on
// ln s_i with the covariance the MODEL implies (GMWM-style, Guerrier et al.): the variance of
// ln s_i is 2/nu_i with nu_i the model's EDF there (Greenhall & Riley EDF of each term's power
// law, model_edf below), never the per-tau noise identification's; the correlation between
// octave points is each power law's (measured, kOctaveCorr in the .cpp) mixed by the terms'
// shares. Every subset of the five terms is fitted (non-negative) and the least AICc (Akaike's
// criterion with the small-sample correction) is the model the goodness of fit is tested on. The
// widest non-negative model on the points (all five terms, theta >= 0, NNLS over the subsets: a
// term the AICc model leaves out would land in its neighbours, R on 6 h read 1.6x with K left
// out) says which terms are reported, with the covariance of the model plus every term left out
// at its upper limit (a term the data cannot exclude still scatters the points); the VALUES are
// the reported terms' model refitted on that covariance (a term the widest model holds but cannot
// tell from 0, Q on a record without it, took a share of N there), and the bounds theirs.
// The bounds hold over every plausible model too (AICc within 2 of the least, Burnham &
// Anderson): a term one of them does without has 0 as its lower bound, and a null's upper limit
// covers what they read for it (collinear terms, K against B + R on one hour, otherwise give
// bounds that exclude the reading of the other model).
// A term is reported (in_model) when AICc selects it or its interval excludes zero; otherwise
// it is null with an upper limit. No record-length rule: R is a candidate on every record. The
// points fitted start where the model describes the curve: the shortest octave points are
// dropped while the AICc model's chi-square is improbable (kGofAlpha), since what the five
// power laws miss on a DUT (folded tones, the output filter) sits at the shortest taus.
// docs/analysis.md ("One model") gives the reasoning and coverage.
// Long-tau points of other estimators (TOTDEV, TheoH: more EDF near T) are not used yet; they
// would enter as further points with their own EDF and the model covariance extended to them.
#pragma once
#include <array>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "analysis/allan.hpp"

namespace rig::analysis {

struct NoiseModelFit {
  bool ok = false;
  std::string reason;
  // per term Q, N, B, K, R (the order of theta above)
  std::array<bool, 5> in_model{};      // reported: selected by AICc or its interval excludes 0
  std::array<double, 5> value{};       // sqrt(theta) of the reported terms' model (0 when not reported)
  std::array<double, 5> lo{}, hi{};    // bounds at `confidence` (in the model)
  std::array<double, 5> upper{};       // every term: upper limit (the interval's upper end)
  std::array<double, 5> upper_method{};  // a null's upper limit at one sigma, whatever `confidence`:
                                         // what the drift's scatter takes it at (noise_terms.cpp)
  std::array<double, 5> share{};       // the term's largest share of the model sigma^2 over the fitted taus
  std::array<double, 5> z{};           // theta / sd(theta) of a term in the model
  std::vector<double> tau_s, avar, edf;  // the points fitted: tau, measured sigma^2, model EDF
  double aicc = 0;          // of the AICc model (the one the goodness of fit is tested on)
  double chi2_per_dof = 0;  // GLS chi2 of the selected model on the covariance it implies, per dof
  double gof_p = 0;         // P(chi2 >= that): the goodness of fit over the points fitted
  std::size_t dropped_short = 0;  // octave points below tau_s.front() left out as not described by the model
  // When the fit on every point failed and leaving out this many of the longest points (at most
  // kLongSagPoints, fewer than the short end needed) fitted: a chance realisation at long tau.
  // Every point is fitted then (gof_p below kGofAlpha, dropped_short 0, no model error); else 0.
  std::size_t long_tau_misfit = 0;
  double model_error = 0;   // relative model error delta (Birge), only when no tau range fitted (gof_p < kGofAlpha,
                            // long_tau_misfit 0)
};

// Goodness of fit: a model whose chi-square has a probability below kGofAlpha does not describe
// the points; the shortest tau is dropped until it does, keeping at least kMinGofPoints points.
inline constexpr double kGofAlpha = 1e-3;
inline constexpr std::size_t kMinGofPoints = 6;
// Unless the widest model fitted past them puts this many times the variance a dropped point
// measured there while the AICc-selected model does not (a term the selection left out that the
// dropped points contradict; noise_model.cpp): then no point is dropped and the misfit is the model
// error. A null term's upper limit is held to this factor too.
inline constexpr double kDroppedContradiction = 30;
// A misfit that leaving out at most this many of the longest points removes, with fewer points
// left out than the short end would need, is a chance realisation at long tau: no short point is
// dropped for it (noise_model.cpp).
inline constexpr std::size_t kLongSagPoints = 3;

// oadev: the overlapping Allan deviation points of one record (any grid; the octave subset
// is taken from it); record_s: its length; confidence: of the bounds and upper limits (default
// one sigma; the values and which terms are reported do not depend on it);
// threads: over which each selection round's 31 subset fits run (the result does not depend on
// it, bit for bit).
NoiseModelFit fit_noise_model(std::span<const DevPoint> oadev, double record_s, double confidence = kOneSigma,
                              unsigned threads = 2);

// The points fit_noise_model starts from, as indices into oadev: the octave subset (from the
// smallest tau, each next at least twice the last) and the longest tau when it is at least 1.5x
// the last of them.
std::vector<std::size_t> octave_points(std::span<const DevPoint> oadev);

// The phase points of a record of record_s seconds sampled every tau0 (its frequency values + 1).
std::size_t phase_points(double record_s, double tau0);

// What the fit assumes of ln s_i at the points (tau_s[i], factor m[i]) of a record of n_phase
// points whose true terms are theta: bias[i] = E[ln(s_i / mu_i)] (the log-chi-square bias at the
// model's EDF) and cov (n x n, row-major) the covariance of ln s_i (2/nu_i and the octave
// correlations, no model error). theta may be in any unit: only the terms' shares matter, and the
// squares are brought to a largest of [0.5, 1) by a power of two (exact) before the covariance
// multiplies them, whose products under- or overflow in a record's own units (1e-80 g, 1e90 g:
// NoiseTerms.TheTermsAreTheSameInAnyUnit). For checking the fit's assumptions against simulation
// (bench/analysis/coverage_noise --covariance) and for the paper method's B bounds.
struct LogScatter {
  std::vector<double> bias, cov;
};
LogScatter model_log_scatter(std::span<const double> tau_s, std::span<const std::size_t> m,
                             const std::array<double, 5>& theta, std::size_t n_phase);

// sigma^2 of term k (0..4 = Q, N, B, K, R) per unit of its squared coefficient at tau (IEEE 952).
double noise_basis(int k, double tau);

// Each term's sigma^2 at tau for coefficients squared theta (theta_k noise_basis(k, tau)), and
// their sum, the model's sigma^2 (added in the order Q..R, so every caller gets the same bits).
std::array<double, 5> term_sigma2(const std::array<double, 5>& theta, double tau);
double model_sigma2(const std::array<double, 5>& theta, double tau);

// The EDF of an overlapping Allan variance at factor m of n_phase points whose true variance is
// the sum of the components mu[k] (independent processes): sd(s) <= sum_k mu_k sqrt(2/nu_k)
// (nu_k: Greenhall & Riley for Q alpha 2, N 0, B -1, K -2; the bound of the cross-covariances by
// Cauchy-Schwarz, exact when all nu_k are equal); the ramp R is deterministic and adds only its
// cross term with the random terms (term_scatter), in quadrature; edf = 2 (sum mu)^2 / var(s).
double model_edf(const std::array<double, 5>& mu, std::size_t m, std::size_t n_phase);

// The standard deviation each term's share contributes to an overlapping Allan variance at
// factor m of n_phase points, mu the terms' Allan variances there: Q, N, B, K mu_k sqrt(2/nu_k)
// (Greenhall & Riley); R (a deterministic ramp) the sd of its cross term with the random terms,
// sqrt(2 mu_R var(ebar)), ebar the mean random second difference (derivation in the .cpp).
// Giving R random walk's EDF instead (the previous version) put the fitted curve 1.2-1.6x above
// the R-dominated points (the log-bias correction of EDF ~2 on points whose scatter is far less).
std::array<double, 5> term_scatter(const std::array<double, 5>& mu, std::size_t m, std::size_t n_phase);

// The part of term_scatter that depends on the point alone: sqrt(2/nu_k) of Q, N, B, K (white PM,
// white FM, flicker FM, random walk FM; Greenhall & Riley) at factor m of n_phase points. The
// fit evaluates the model's EDF and covariance thousands of times on the same points, so it
// computes these once per point and passes them to the overloads below (the same values: bit
// for bit what the three-argument forms compute).
std::array<double, 4> random_term_factors(std::size_t m, std::size_t n_phase);
std::array<double, 5> term_scatter(const std::array<double, 5>& mu, const std::array<double, 4>& factors, std::size_t m,
                                   std::size_t n_phase);
double model_edf(const std::array<double, 5>& mu, const std::array<double, 4>& factors, std::size_t m,
                 std::size_t n_phase);

}  // namespace rig::analysis
