// Allan-family deviations with Stable32-compatible term counts, tau grids, noise
// identification and Greenhall-Riley confidence bounds (NIST SP 1065; IEEE Std 1139).
//
// Frequency data y (accelerometer output, g) is integrated to the phase x = cumsum(y)*tau0;
// every estimator works on the phase. tau = m * tau0, tau0 = 1/rate_hz. N below is the
// number of PHASE points (frequency points + 1).
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace rig::analysis {
struct Drift;  // drift.hpp

enum class DataKind { Frequency, Phase };
enum class Deviation { ADEV, OADEV, MDEV, TDEV, HDEV, OHDEV, TOTDEV };

const char* to_string(Deviation d);   // "adev", "oadev", ...
const char* to_string(DataKind k);    // "freq", "phase"
Deviation parse_deviation(const std::string& s);  // throws std::invalid_argument
DataKind parse_data_kind(const std::string& s);   // "freq"|"frequency"|"phase"

struct TauGrid {
  enum Kind { Octave, Decade, All, Log } kind = Kind::Octave;
  int log_n = 100;  // points per full span for Kind::Log (log-spaced, duplicates merged)
};
TauGrid parse_tau_grid(const std::string& s);  // "octave|decade|all|log:N", throws std::invalid_argument
// The `all` grid asks for every averaging factor up to max_factor, each a sum over the record:
// about max_factor * N term sums, growing as N^2 (1e6 values ran past 10 min). `rig analyze` and
// a profile's [analysis] taus refuse more term sums than this (about 5 s on the rig's machines).
inline constexpr double kAllTermSums = 4e9;

// Largest averaging factor Stable32 evaluates for this deviation on N phase points:
// ADEV, HDEV (N-1)/5; OADEV, MDEV, TDEV, OHDEV (N-1)/4; TOTDEV (N-1)/2.
std::size_t max_factor(Deviation d, std::size_t n_phase);
// The averaging factors m of a grid (octave 1,2,4..; decade 1,2,4,10,20,40..; all 1..max;
// log:N q = max(1, ceil((N-1) / log2 max)) points per octave over [1, max]: below 64 rounded
// from 2^(k/q), repeats dropped; from 64 on the q seeds 64 2^(j/q) in [64, 128), rounded, times
// powers of two, so that every m has 2m in the grid (which halves the engine's memory traffic,
// see allan_stream.cpp). About N points, but never fewer than one per octave (log:2 is the
// octave grid) nor, from 64 on, more than 64 (docs/analysis.md); stopped at max_factor.
std::vector<std::size_t> tau_factors(const TauGrid& g, Deviation d, std::size_t n_phase);

// Number of terms Stable32 prints in its '#' column (see tests/data/allan-reference/README.md).
std::size_t term_count(Deviation d, std::size_t n_phase, std::size_t m);
// Whether the deviation has at least one term at factor m of n_phase points (TOTDEV: m up to
// (N-1)/2): the factors an explicit list (DevOptions::factors) may ask for, beyond the grids'
// Stable32 caps (max_factor).
bool factor_in_range(Deviation d, std::uint64_t n_phase, std::size_t m);

struct DevPoint {
  std::size_t m = 0;
  double tau_s = 0;
  std::size_t n_terms = 0;
  double dev = 0, lo = 0, hi = 0;  // lo/hi: chi-square bounds at DevOptions::confidence (0 if bounds off)
  double edf = 0;
  int alpha = 0;  // identified power-law exponent of S_y(f) (Stable32's identification)
  // The exponent whose EDF the bounds use: alpha, or, where the EDF guard capped the EDF of a
  // B1-identified tau, the type the lag-1 ACF found at the longest tau below (DevOptions::edf_guard).
  int edf_alpha = 0;
};

// The default confidence of the bounds: exactly one sigma, erf(1/sqrt 2). Stable32 prints it
// as "0.683"; its tables' bounds are at this value (tests/analysis/test_allan_reference.cpp).
inline constexpr double kOneSigma = 0.6826894921370859;

struct DevOptions {
  Deviation type = Deviation::OADEV;
  DataKind data = DataKind::Frequency;
  double rate_hz = 1.0;
  TauGrid taus;
  double confidence = kOneSigma;
  bool bounds = true;
  std::vector<std::size_t> factors;  // explicit averaging factors; overrides `taus` when not empty
  unsigned threads = 0;              // 0 = all hardware threads (the 2-core rig PC: both)
  std::optional<int> fixed_alpha;    // skip identification and use this noise type (Stable32's manual choice)
  // EDF guard: at taus with fewer than 30 averages (B1 rule), the EDF is at most that of the
  // noise type the lag-1 ACF identified at the longest tau below (docs/analysis.md). Off:
  // Stable32's bounds exactly.
  bool edf_guard = true;
  // Cancellation hook: called between units of work (about every chunk of phase points and per
  // tau, from any worker thread); it may throw to stop the computation, and that exception
  // leaves deviation() after the workers stop. The math knows nothing of what it throws.
  std::function<void()> poll;
};

// The index of the first NaN or infinity in `v`, if any. One vectorised pass over the values
// (the check every reader of raw records makes), then a search only when there is one.
std::optional<std::size_t> first_non_finite(std::span<const double> v);

// No measurement in any unit the rig records (g, rad, s) comes near this magnitude: a value
// at or beyond it is a corrupt record, and the phase sums and squared differences of a long
// record of such values would overflow to inf (1e308 values gave every deviation inf). Readers
// reject it like NaN and inf. 2^333 (about 1.7e100): scaling by 2^691 overflows exactly there,
// which makes the check one multiply per value.
inline constexpr double kMaxMagnitude = 0x1p333;
// The index of the first value that is NaN, infinite or not below kMaxMagnitude in magnitude,
// if any (vectorised like first_non_finite).
std::optional<std::size_t> first_unusable(std::span<const double> v);

// In-memory computation. Throws std::invalid_argument for fewer than 3 phase points,
// a non-positive rate or a non-finite or out-of-range value (naming its index).
std::vector<DevPoint> deviation(std::span<const double> data, const DevOptions& opt);

// ---- streaming: records too large for memory (50 h at 1 kHz = 1.8e8 samples) ----
// A random-access source of the raw values (frequency or phase, as DevOptions::data says),
// e.g. pread() over a float64 file. read_at may be called from several threads at once
// for disjoint or overlapping ranges; it returns the number of values delivered (short
// only at the end) and throws on a read error.
struct ChunkSource {
  virtual ~ChunkSource() = default;
  virtual std::uint64_t size() const = 0;
  virtual std::size_t read_at(std::uint64_t pos, std::span<double> out) const = 0;
  // All values contiguous in memory, if the source has them so (saves a copy per read).
  virtual const double* contiguous() const { return nullptr; }
  // A source may leave its contiguous() values unchecked until the analysis's sequential pass
  // reaches them (a mapped file: checked while the pass has them in cache, instead of one more
  // pass over the file before it). The engine calls this on every range of values of that pass
  // before it uses them, in order from 0 (or, split in two parts, reporting the lower part's
  // refusal first); it throws naming the first unusable value of the range. Re-reads through
  // read_at() stay the source's business. The default: values checked already.
  virtual void check_range(std::uint64_t pos, std::size_t len) const {
    (void)pos, (void)len;
  }
  // The engine is about to read contiguous() values [pos, pos + len) from the calling thread: a
  // mapped source may fault their pages in now, in one call (each of the engine's two build
  // threads for its own part, so the page-ins are shared, not left to whichever thread reads
  // first). Advisory.
  virtual void will_read(std::uint64_t pos, std::size_t len) const {
    (void)pos, (void)len;
  }
};

// A ChunkSource over values already in memory (used by deviation() and by tests).
class SpanSource final : public ChunkSource {
 public:
  explicit SpanSource(std::span<const double> v) : v_(v) {}
  std::uint64_t size() const override { return v_.size(); }
  std::size_t read_at(std::uint64_t pos, std::span<double> out) const override;
  const double* contiguous() const override { return v_.data(); }

 private:
  std::span<const double> v_;
};

struct StreamOptions {
  std::size_t memory_budget_bytes = 384u << 20;  // ring of phase points + per-tau state
  std::size_t chunk = 1u << 14;                  // phase points per processing step (L2-sized windows)
  std::function<void()> poll;                    // as DevOptions::poll (deviations_stream takes the options')
  // When set, deviations_stream also writes the record's least-squares drift there (drift.hpp),
  // from sums its pass keeps (no pass of its own).
  Drift* drift = nullptr;
  // When set, the largest |P| of the pass's phase (allan_engine.hpp EngineResult::phase_abs_max),
  // in the engine's units (frequency sums; phase data as phase x rate): its rounding floor.
  double* phase_abs_max = nullptr;
};

// Streams the source once sequentially (plus random-access cursors for the few factors
// whose span exceeds the ring), both cores. The result equals deviation() on the same
// values to rounding (tests/analysis: stream_matches_memory).
std::vector<DevPoint> deviation_stream(const ChunkSource& src, const DevOptions& opt, const StreamOptions& so = {});

// Several deviation types in one pass over the source (each DevOptions must agree on
// data kind and rate). Used by `rig analyze` to get OADEV and e.g. MDEV together.
std::vector<std::vector<DevPoint>> deviations_stream(const ChunkSource& src, std::span<const DevOptions> opts,
                                                     const StreamOptions& so = {});

}  // namespace rig::analysis
