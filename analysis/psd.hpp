// Power spectral density by Welch's method (averaged modified periodograms; FFTW), peak
// list with prominence, and the white-noise level that cross-checks N from the Allan
// curve: for white frequency noise S_y(f) = h0 and sigma^2(tau) = h0 / (2 tau), so N^2 = h0 / 2.
#pragma once
#include <cstddef>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "analysis/allan.hpp"

namespace rig::analysis {

enum class Window { Hann, Hamming, Blackman, Rectangular };
Window parse_window(const std::string& s);  // hann|hamming|blackman|rect, throws std::invalid_argument
const char* to_string(Window w);

struct WelchOptions {
  std::size_t segment = 0;  // points per segment; 0 = auto (power of two, about n/8, 256..65536)
  double overlap = 0.5;     // fraction of a segment, [0, 0.95]
  Window window = Window::Hann;
  bool detrend_mean = true;  // remove each segment's mean (the bias is not noise)
  unsigned threads = 0;      // 0 = all hardware threads; the result does not depend on it
  std::function<void()> poll;  // cancellation hook, as analysis::DevOptions::poll (called per segment)
};

struct Psd {
  std::vector<double> f_hz, psd;  // one-sided, unit^2/Hz
  std::vector<double> asd;        // sqrt(psd), unit/sqrt(Hz)
  std::size_t segment = 0, segments = 0;
  double rate_hz = 0, enbw_hz = 0;  // equivalent noise bandwidth of one bin
  // A bin's equivalent degrees of freedom: noise gives S chi2(dof)/dof. 2 per segment, less where
  // the segments overlap (Welch 1967: var/S^2 = (1/K)[1 + 2 sum_j (1 - j/K) rho(j)^2], rho(j)
  // the window's overlap correlation at j steps; dof = 2 S^2/var).
  double dof = 0;
};

// The segment length welch() uses on n values: opt.segment, or the automatic choice. A caller
// checks n >= it before a long computation, instead of learning it from welch() afterwards.
std::size_t welch_segment(std::uint64_t n, const WelchOptions& opt);

// Throws std::invalid_argument when x is shorter than one segment or options are out of range.
Psd welch(std::span<const double> x, double rate_hz, const WelchOptions& opt = {});

// The same from a random-access source (segments read one at a time: bounded memory).
Psd welch(const ChunkSource& src, double rate_hz, const WelchOptions& opt = {});

struct Peak {
  double f_hz = 0, psd = 0, prominence_db = 0;
};
// Local maxima whose prominence (height above the higher of the two lowest points separating
// them from higher ground, as scipy.signal.find_peaks) is at least min_prominence_db, strongest
// first, and, where the bins have fewer than kPeakNoiseRuleDof degrees of freedom, that noise
// alone would not give: the bin stands above the median of the bins around it (+-64, its own +-3
// left out) by the chi2(dof) quantile that white noise exceeds anywhere in the spectrum with
// probability `false_alarm`. With one segment each bin is chi2(2): a 10 dB prominence over the
// dips around it came by chance, a dozen "peaks" in 300 white values (a review). With more
// degrees of freedom the dips are shallow and the prominence alone holds; the neighbourhood's
// median would there hide a resonance wider than it (a code review: Q = 10 at 20 Hz, 24 dB, on
// 2^20 values at 1 kHz).
inline constexpr double kPeakNoiseRuleDof = 30;
std::vector<Peak> find_peaks(const Psd& p, double min_prominence_db = 10.0, std::size_t max_peaks = 20,
                             double false_alarm = 0.01);

// White level h0 over [f_lo, f_hi] (median of the bins, corrected to the mean of the chi-square
// spread so that tones barely move it); unit^2/Hz.
double white_level(const Psd& p, double f_lo, double f_hi);

// The IEEE 952 terms from the PSD of the output y (one-sided, tau0 = 1/rate):
//   S(f) = Q^2 8 sin^2(pi f tau0)/tau0 + 2 N^2 + B^2/(pi f) + K^2/(2 pi^2 f^2)
// (white phase Q: y = (e_n - e_{n-1})/tau0 with var e = Q^2, rising as f^2; white rate N,
// S = 2 N^2; flicker, S = h_-1/f with h_-1 = B^2/pi, the level whose Allan variance is
// (2 ln2/pi) B^2; rate random walk K, S = K^2/(2 pi^2 f^2); IEEE 952 Annex C / NIST SP 1065
// Table 2 in these units). Fitted to the Welch bins in [f_lo, f_hi] by non-negative least
// squares on the relative scale (each bin ~ S chi2(2 segments)/(2 segments): weights 1/S_model^2,
// iterated), the best of the non-negative active sets. N = the cross-check of the Allan N that
// quantisation (Q) does not bias, unlike white_level's median.
struct PsdTerms {
  bool ok = false;
  double Q = 0, N = 0, B = 0, K = 0;  // g*s, g*s^0.5, g, g/s^0.5
  std::size_t bins = 0, left_out = 0;  // bins fitted; bins of the band left out around peaks
};
// Bins within +-3 of a peak in `leave_out` (the window's main lobe) are not fitted: a tone is no
// noise term, and a review's 72 Hz line in white noise read 2.4x the N (`left_out` counts them).
PsdTerms psd_noise_fit(const Psd& p, double f_lo, double f_hi, std::span<const Peak> leave_out = {});

// The cross-check's note ("" when there is nothing to say): the PSD's N more than 1.5x from the
// Allan N (a PSD bin's scatter over hundreds of bins is a few %, the Allan N's bounds tighter
// still), or none of the band given to N by the PSD model while the Allan model has an N (it
// neither confirms nor contradicts: printed as N = 0 without a word before, a review).
// allan_n <= 0: the Allan model has no N. Over f_lo..f_hi Hz.
std::string psd_n_note(double allan_n, double psd_n, bool psd_fit_ok, double f_lo, double f_hi);

}  // namespace rig::analysis
