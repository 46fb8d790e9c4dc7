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
// them from higher ground, as scipy.signal.find_peaks) is at least min_prominence_db, strongest first.
std::vector<Peak> find_peaks(const Psd& p, double min_prominence_db = 10.0, std::size_t max_peaks = 20);

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
  std::size_t bins = 0;
};
PsdTerms psd_noise_fit(const Psd& p, double f_lo, double f_hi);

// The cross-check's note ("" when there is nothing to say): the PSD's N more than 1.5x from the
// Allan N (a PSD bin's scatter over hundreds of bins is a few %, the Allan N's bounds tighter
// still), or none of the band given to N by the PSD model while the Allan model has an N (it
// neither confirms nor contradicts: printed as N = 0 without a word before, a review).
// allan_n <= 0: the Allan model has no N. Over f_lo..f_hi Hz.
std::string psd_n_note(double allan_n, double psd_n, bool psd_fit_ok, double f_lo, double f_hi);

}  // namespace rig::analysis
