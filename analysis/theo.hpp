// Long-tau estimators: Theo1, TheoH (Theo1 hybrid with AVAR, bias-removed), and the total
// family's MTOT, TTOT and HTOT, each with an equivalent number of degrees of freedom so that
// their chi-square bounds are honest (NIST SP 1065, sec. 5.2.11-5.2.15 and 5.5; Howe & Tasset,
// "Theo1: characterization of very long-term frequency stability", EFTF 2004; Howe, Taylor &
// Tasset, "TheoH bias-removal method", IFCS 2006). Math only: no I/O.
//
// These extend the curve where the Allan variance has few terms: Theo1 reaches tau = 0.75 T
// (T the record length), the total variances T/3, all with more degrees of freedom than
// OADEV at the same tau. The noise fit (noise_terms) takes LongTauPoint views of them
// (docs/analysis.md, "Long-tau statistics").
#pragma once
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "analysis/allan.hpp"

namespace rig::analysis {

enum class LongTau { Theo1, TheoH, MTOT, TTOT, HTOT };
const char* to_string(LongTau s);                 // "theo1", "theoh", "mtot", "ttot", "htot"
std::optional<LongTau> parse_long_tau(const std::string& s);  // nullopt: not one of them

// One point of a long-tau statistic. The same fields as DevPoint (so a fit can treat both
// alike) plus what is particular to these estimators.
struct LongTauPoint {
  std::size_t m = 0;        // averaging factor; Theo1/TheoH-Theo1 points: the Theo1 m (even)
  double tau_s = 0;         // Theo1: 0.75 m tau0 (SP 1065 eq. 30); the others: m tau0
  std::size_t n_terms = 0;  // squared terms actually summed
  double dev = 0;           // the deviation; MTOT/TTOT/HTOT bias-corrected for `alpha` (see dev_raw)
  double dev_raw = 0;       // the statistic as defined (Stable32 prints this), before bias removal
  double lo = 0, hi = 0;    // chi-square bounds of `dev` at the requested confidence (0: bounds off)
  double edf = 0;
  int alpha = 0;            // noise type used for the EDF and the bias removal
  std::size_t stride = 1;   // 1: every subsequence summed; k: every k-th (work cap, see LongTauOptions)
  std::string estimator;    // TheoH: "avar" (OADEV) or "theobr" (bias-removed Theo1); else the statistic
  // Non-empty where the table EDF gives no interval to state (lo, hi, edf NaN): why. SP 1065's
  // Theo1 EDF for random-walk FM is negative for m above about 0.84 N, and an EDF far below 1 gave
  // lo > dev (a review: EDF -0.21 with [0, 0], EDF 0.02 with lo 1700x the value).
  std::string bounds_note;
};

struct LongTauOptions {
  LongTau type = LongTau::Theo1;
  DataKind data = DataKind::Frequency;
  double rate_hz = 1.0;
  TauGrid taus;                        // grid of m (Theo1: rounded to even m, up to N-1)
  std::vector<std::size_t> factors;    // explicit m, overrides `taus`
  double confidence = kOneSigma;
  bool bounds = true;
  std::optional<int> fixed_alpha;      // noise type for EDF and bias instead of identification
  // Noise types come from OADEV's identification (its edf_alpha, after the EDF guard) at the
  // nearest tau at or below the point's: the process's noise type does not depend on the estimator. Empty: an
  // octave OADEV of the same data is computed for it.
  std::vector<DevPoint> noise_ref;
  // Work cap: at most about this many squared terms per tau. Beyond it every k-th subsequence
  // start is summed (at least kMinStarts of them, spread over the record); the point says k.
  // Exact (k = 1) on every tau for records up to ~6900 points (the total family, 1.25 N^2 terms
  // at m = N/6) and ~21000 (Theo1, N^2/8 at m = N/2); docs/analysis.md has the cost.
  double max_terms_per_tau = 6.0e7;
  unsigned threads = 0;                // 0 = all cores
  std::function<void()> poll;          // cancellation hook, as DevOptions::poll
};

// Subsequence starts kept at least, whatever the cap (spread evenly over the record).
inline constexpr std::size_t kMinStarts = 64;

// ---- the statistics on phase data x (N points, tau0 apart); stride: sum every k-th start ----
struct VarSum {
  double var = 0;           // the variance
  std::size_t terms = 0;    // squared terms summed
};

// Theo1, SP 1065 eq. (30), m even, 2 <= m <= N-1 (i, delta from 0):
//   Theo1(m) = 1 / (0.75 (N-m) (m tau0)^2) sum_{i=0}^{N-m-1} sum_{d=0}^{m/2-1}
//              [ (x_i - x_{i+m/2-d}) + (x_{i+m} - x_{i+m/2+d}) ]^2 / (m/2 - d)
VarSum theo1_var(std::span<const double> x, std::size_t m, double tau0, std::size_t stride = 1);

// MTOT, SP 1065 eq. (27) (Howe & Vernotte 1999): for each of the N-3m+1 subsequences of 3m
// phase points, remove the frequency offset (difference of the half means over their
// spacing), extend by uninverted even reflection to 9m points, and take the 6m modified
// second differences of m-averages:
//   Mtot(m) = 1 / (2 (m tau0)^2 (N-3m+1)) sum_n (1/6m) sum_{j} [ (X_{j+2m} - 2 X_{j+m} + X_j)/m ]^2
// with X_j the m-point phase sums of the extended sequence. TTOT = (tau^2/3) MTOT (eq. 28,
// with tau^2: SP 1065 prints tau^3 there, a typo).
VarSum mtot_var(std::span<const double> x, std::size_t m, double tau0, std::size_t stride = 1);

// HTOT, SP 1065 eq. (29) (Howe, Beard, Greenhall, Riley 2000): the same on the N-1 frequency
// values y: each 3m subsequence has its linear frequency drift removed (half means), is
// reflected to 9m and gives 6m Hadamard differences of m-averages,
//   Htot(m) = 1 / (N-1-3m+1) sum_n (1/6m) sum_j (1/6) [ ybar_j - 2 ybar_{j+m} + ybar_{j+2m} ]^2,
// m >= 2 (at m = 1 SP 1065 and Stable32 use the overlapping Hadamard variance).
VarSum htot_var(std::span<const double> x, std::size_t m, double tau0, std::size_t stride = 1);

// ---- equivalent degrees of freedom (N phase points) ----
// Theo1, SP 1065 sec. 5.5.5 (Howe & Tasset), r = 0.75 m, alpha 2..-2:
//   WPM  0.86 (N+1)(N - 4r/3) / (N - r) * r / (r + 1.14)
//   FPM  (4.798 N^2 - 6.374 N r + 12.387 r) / (sqrt(r + 36.6) (N - r)) * r / (r + 0.3)
//   WFM  [ (4.1 N + 0.8)/r - (3.1 N + 6.5)/N ] * r^1.5 / (r^1.5 + 5.2)
//   FFM  (2 N^2 - 1.3 N r - 3.5 r) / (N r) * r^3 / (r^3 + 2.3)
//   RWFM (4.4 N - 2)/(2.9 r) * [ (4.4 N - 1)^2 - 8.6 r (4.4 N - 1) + 11.4 r^2 ] / (4.4 N - 3)^2
double edf_theo1(int alpha, std::size_t n_phase, std::size_t m);
// MTOT and TTOT, SP 1065 Table 8 (Howe's revised fit, as Stable32 uses it), m > 8:
// edf = b (N/m) - c, (b, c) = WPM (2.16, 2.28), FPM (1.73, 2.99), WFM (1.33, 1.89),
// FFM (0.92, 0.76), RWFM (0.79, 0.37); m <= 8: the MVAR (Greenhall-Riley) EDF.
double edf_mtot(int alpha, std::size_t n_phase, std::size_t m);
// HTOT, SP 1065 Table 9: edf = (N/m) / (b0 + b1 m/N), (b0, b1) = WFM (0.559, 1.004),
// FFM (0.868, 1.140), RWFM (0.938, 1.696), FWFM (0.974, 2.554), RRFM (1.276, 3.149), m > 16;
// PM noise and m <= 16 (outside the fit) take the overlapping Hadamard EDF (Greenhall-Riley).
double edf_htot(int alpha, std::size_t n_phase, std::size_t m);

// Bias of the total variances relative to MVAR (MTOT, TTOT) and HVAR (HTOT), E[tot]/E[var] by
// noise type (SP 1065 sec. 5.2.11 and 5.2.14): MTOT 0.94, 0.83, 0.73, 0.70, 0.69 for alpha
// 2..-2; HTOT 0.995, 0.851, 0.771, 0.717, 0.679 for alpha 0..-4 (1 for PM). dev = dev_raw/sqrt(a).
double tot_bias(LongTau s, int alpha);

// The statistic on a record (frequency or phase, as opt.data says). Throws std::invalid_argument
// for fewer than 3 phase points (TheoH, Theo1: 4), a non-positive rate or a non-finite value.
std::vector<LongTauPoint> long_tau(std::span<const double> data, const LongTauOptions& opt);

// The noise type of `noise_ref` at tau: the `edf_alpha` (the type after the EDF guard) of the
// point at the largest tau <= it (the first point if none); 0 (white FM) for an empty list.
int alpha_at(std::span<const DevPoint> noise_ref, double tau_s);

// Phase from the record, less the line through its end points (every statistic here ignores
// a linear phase, and removing it keeps the sums well-conditioned for a large offset).
std::vector<double> detrended_phase(std::span<const double> data, DataKind kind, double rate_hz);

}  // namespace rig::analysis
