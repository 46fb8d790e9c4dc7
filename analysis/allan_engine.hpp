// Internal: the one-pass engine behind deviation() and deviation_stream().
//
// The phase P is built once, sequentially, into a ring of R points; every requested
// (deviation, m) pair is an accumulator that consumes, chunk by chunk, the terms whose
// highest phase index has just arrived. Each tau is O(N), all taus share one read of the
// data, both cores split the accumulators of each chunk. Accumulators whose span does
// not fit the ring ("far") are run afterwards from sequential cursors that rebuild P from
// checkpoints, so memory stays bounded whatever N is.
#pragma once
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "analysis/allan.hpp"
#include "analysis/parallel.hpp"

namespace rig::analysis::detail {

// Internal phase P in "frequency-sum" units: for frequency data P[j] = sum_{k<j} (y[k] - c),
// for phase data P[j] = (x[j] - x[0] - s j) / tau0. The shift c and slope s only add a linear
// function of j, which every estimator here annihilates (second/third differences, and the
// odd reflection of TOTDEV), and they keep P small so rounding stays at the data's level.
struct PhaseSpec {
  DataKind kind = DataKind::Frequency;
  double rate_hz = 1;
  std::uint64_t n_src = 0;  // source values
  std::uint64_t n = 0;      // phase points
  double shift = 0;         // c (frequency)
  double x0 = 0, slope = 0; // phase
};

// Raw sums of one (deviation, m) pair after the pass.
struct Sums {
  Deviation type{};
  std::size_t m = 0;
  double sum = 0;               // sum of squared differences in P units
  std::size_t terms = 0;
  bool decimated_complete = true;  // EngineResult::decimated[m] holds every P[k m]
};

// P[k m], k = 0 .. size() - 1, for noise identification: a strided view of the ring when it holds
// the whole record (no copy: the series of 108 taus would be some 25 MB of fresh pages), else the
// points collected during the pass.
class Decimated {
 public:
  Decimated() = default;
  Decimated(const double* base, std::size_t stride, std::size_t count) : base_(base), stride_(stride), count_(count) {}
  explicit Decimated(std::vector<double> own) : own_(std::move(own)), base_(own_.data()), count_(own_.size()) {}
  Decimated(Decimated&& o) noexcept { *this = std::move(o); }
  Decimated& operator=(Decimated&& o) noexcept {
    const bool owns = o.base_ == o.own_.data() && !o.own_.empty();
    own_ = std::move(o.own_);
    base_ = owns ? own_.data() : o.base_;
    stride_ = o.stride_, count_ = o.count_;
    return *this;
  }
  std::size_t size() const { return count_; }
  double operator[](std::size_t k) const { return base_[k * stride_]; }

 private:
  std::vector<double> own_;
  const double* base_ = nullptr;
  std::size_t stride_ = 1, count_ = 0;
};

struct EngineRequest {
  Deviation type;
  std::size_t m;
};

struct EngineResult {
  PhaseSpec spec;
  std::vector<Sums> sums;  // same order as the requests
  // P[k m], k = 0.. (capped), for noise identification: one series per distinct m, shared by
  // the deviations that use that m (counted in the memory budget once when copied). A view into
  // the engine's ring when it holds the record: valid while the Engine lives.
  std::map<std::size_t, Decimated> decimated;
  std::size_t ring_points = 0, far_count = 0;
  // The sum of P[0 .. n-1] over the pass and P[n-1]: the record's drift (drift.hpp) at no pass of
  // its own; the same bits on one thread or two (summed per block, allan_stream.cpp PhaseSums).
  double phase_sum = 0, phase_last = 0;
  // The largest |P| at the checkpoints and the end: the scale of the phase's rounding (a frequency
  // drift makes P grow as j^2, and every difference of P carries its units in the last place).
  double phase_abs_max = 0;
};

// One analysis of one source: run() makes the pass; extra() afterwards computes one more
// (type, m) sum by random access (from the ring when it holds the whole record, else from
// cursors over the source), for the R(n) noise test that only some taus need.
class Engine {
 public:
  Engine(const ChunkSource& src, DataKind kind, double rate_hz, const StreamOptions& so, unsigned threads,
         std::size_t noise_id_cap);
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;
  EngineResult run(const std::vector<EngineRequest>& req);
  Sums extra(Deviation type, std::size_t m);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rig::analysis::detail
