// Noise generators of the emulated DUT: cheap, deterministic, portable.
// PRNG: xoshiro256** (Blackman & Vigna 2018) seeded through splitmix64, one
// independent stream per noise source, so adding a source leaves the others'
// sequences unchanged. Normal deviates: Irwin-Hall sum of four 16-bit uniforms
// from one 64-bit draw (mean 0, variance 1, tails cut at +-3.46 sigma): about
// 10x cheaper than Box-Muller, bit-identical on every platform (integer
// arithmetic and one multiply), and the Allan/PSD analysis sees only second moments.
#pragma once
#include <algorithm>
#include <cmath>
#include <span>
#include <numbers>
#include <cstdint>
#include <vector>

#include "design/filter.hpp"

namespace rig::plant::noise {

inline uint64_t splitmix64(uint64_t& s) {
  uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

class Rng {
 public:
  Rng() : Rng(0, 0) {}
  Rng(uint64_t seed, uint64_t stream) {
    uint64_t s = seed ^ (stream * 0xd1b54a32d192ed03ULL);
    for (auto& w : s_) w = splitmix64(s);
  }
  uint64_t next() {
    const uint64_t r = rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return r;
  }
  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  // Approximately standard normal (see the file comment).
  double normal() {
    const uint64_t r = next();
    // The four 16-bit fields summed two at a time in 32-bit lanes of one word (no lane can
    // carry into the next: each holds at most 2 * 65535); the same integer as adding them one by one.
    constexpr uint64_t kFields02 = 0x0000ffff0000ffffULL;
    const uint64_t pairs = (r & kFields02) + ((r >> 16) & kFields02);
    const int64_t sum = static_cast<int64_t>((pairs & 0xffffffffULL) + (pairs >> 32));
    // sum of 4 U{0..65535}: mean 4*32767.5, variance 4*(65536^2-1)/12
    constexpr double kMean = 4 * 32767.5;
    constexpr double kInvSd = 1.0 / 37837.22695;  // 1/sqrt(4*(65536^2-1)/12)
    return (static_cast<double>(sum) - kMean) * kInvSd;
  }

 private:
  static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t s_[4];
};

// Band-limited noise: white noise through a constant-peak-gain band-pass (RBJ
// cookbook) between f_lo and f_hi, scaled to the requested RMS.
class BandNoise {
 public:
  BandNoise() = default;
  BandNoise(double f_lo, double f_hi, double rate_hz, double rms);
  double step(Rng& rng) { return sec_.step(scale_ * rng.normal()); }

 private:
  design::Section sec_;  // the one DF-II-T biquad (design/filter.hpp)
  double scale_ = 0;
};

// Flicker (1/f) noise: a bank of first-order Gauss-Markov processes, three per
// decade of correlation time with equal variances (their Lorentzian spectra sum
// to 1/f between 1/(2 pi tau_max) and 1/(2 pi tau_min)). Each process is updated
// only every ~tau/50 of its own, which keeps the cost per output period tiny.
class FlickerBank {
 public:
  FlickerBank() = default;
  // `b` = the bias-instability coefficient an Allan analysis reads on the flat part
  // (sigma_flat = 0.664 B, IEEE 952 C.1), set from the bank's analytic Allan variance.
  // The processes start in their stationary distribution, drawn from `rng`.
  FlickerBank(double b, double tau_min, double tau_max, double dt, Rng& rng);
  double step(Rng& rng);  // advance by dt, return the sum
  // Analytic Allan deviation of the bank (Gauss-Markov AVAR summed over processes).
  double adev(double tau) const { return sd_ * adev_unit(tau); }

 private:
  struct Proc {
    double tau, phi, drive, value;
    uint32_t every, count;
  };
  double adev_unit(double tau) const;  // with unit variance per process
  std::vector<Proc> procs_;
  // Steps since the counts were last brought up to date, and the steps until the next process
  // is due: between updates a step touches no process (most steps at dt = 1 ms).
  uint32_t elapsed_ = 0, due_ = 1;
  double sum_ = 0;
  double sd_ = 0;  // standard deviation of each process
};

// First-order Gauss-Markov process started at 0 (a quantity that wanders away from its
// power-on value and is pulled back over `tau`). Its white drive has the rate-random-walk
// coefficient `k` (g/sqrt(s)): for t, Allan tau << `tau` it is a random walk,
// sigma(tau) = k sqrt(tau/3) (IEEE 952 C.1), its variance k^2 t; stationary sd k sqrt(tau/2).
class GaussMarkov {
 public:
  GaussMarkov() = default;
  GaussMarkov(double k, double tau, double dt)
      : phi_(std::exp(-dt / tau)), drive_(k * std::sqrt(tau / 2 * (1 - phi_ * phi_))) {}
  double step(Rng& rng) {
    if (drive_ != 0) v_ = phi_ * v_ + drive_ * rng.normal();
    return v_;
  }
  double value() const { return v_; }

 private:
  double phi_ = 1, drive_ = 0, v_ = 0;
};

// Narrow-band interference: `lines` carriers spread evenly over [f_lo, f_hi], each with
// a complex envelope that wanders as a Gauss-Markov process of correlation time
// `coherence_s` (line width ~ 1/(pi coherence)); no spectral skirts, so nothing leaks
// to frequencies outside the band (which sampling at 1 kHz would fold to near-DC).
class LineBand {
 public:
  LineBand() = default;
  LineBand(double f_lo, double f_hi, int lines, double coherence_s, double rms, double rate_hz, double env_dt,
           Rng& rng);
  void update_envelopes(Rng& rng);  // once per env_dt
  double step() {                   // once per 1/rate_hz
    double v = 0;
    for (Line& l : lines_) {
      v += l.ar * l.c - l.ai * l.s;
      const double nc = l.c * l.rc - l.s * l.rs;
      l.s = l.s * l.rc + l.c * l.rs;
      l.c = nc;
    }
    return v;
  }
  // out[k] = the k-th of the next out.size() step() values, the same bits: per k the lines add
  // in step()'s order. Two lines share one SSE2 register (a pair's carriers), and up to three
  // pairs advance side by side in one pass over the span: their rotations are independent
  // chains the core overlaps, and each out[k] is read and written once per three pairs. No FMA
  // is involved (a vector multiply or add rounds each lane as the scalar one does).
  void fill(std::span<double> out) {
    std::fill(out.begin(), out.end(), 0.0);
    std::size_t j = 0;
    for (; j + 6 <= lines_.size(); j += 6) fill_pairs<3>(&lines_[j], out);
    if (j + 4 <= lines_.size()) {
      fill_pairs<2>(&lines_[j], out);
      j += 4;
    }
    if (j + 2 <= lines_.size()) {
      fill_pairs<1>(&lines_[j], out);
      j += 2;
    }
    for (; j < lines_.size(); ++j) {
      Line w = lines_[j];
      for (double& v : out) {
        v += w.ar * w.c - w.ai * w.s;
        const double nc = w.c * w.rc - w.s * w.rs;
        w.s = w.s * w.rc + w.c * w.rs;
        w.c = nc;
      }
      lines_[j] = w;
    }
  }

 private:
  struct Line {
    double c, s, rc, rs;  // carrier (recursive rotation)
    double ar, ai;        // complex envelope
  };
  // Lines l[0 .. 2P) added to out (fill()'s order), P pairs side by side.
  template <std::size_t P>
  static void fill_pairs(Line* l, std::span<double> out) {
    using v2 = double __attribute__((vector_size(16)));
    v2 c[P], sn[P], rc[P], rs[P], ar[P], ai[P];
    for (std::size_t p = 0; p < P; ++p) {
      const Line &a = l[2 * p], &b = l[2 * p + 1];
      c[p] = v2{a.c, b.c};
      sn[p] = v2{a.s, b.s};
      rc[p] = v2{a.rc, b.rc};
      rs[p] = v2{a.rs, b.rs};
      ar[p] = v2{a.ar, b.ar};
      ai[p] = v2{a.ai, b.ai};
    }
    for (double& v : out) {
      double acc = v;
      for (std::size_t p = 0; p < P; ++p) {
        const v2 t = ar[p] * c[p] - ai[p] * sn[p];
        acc += t[0];
        acc += t[1];
        const v2 nc = c[p] * rc[p] - sn[p] * rs[p];
        sn[p] = sn[p] * rc[p] + c[p] * rs[p];
        c[p] = nc;
      }
      v = acc;
    }
    for (std::size_t p = 0; p < P; ++p) {
      l[2 * p].c = c[p][0];
      l[2 * p + 1].c = c[p][1];
      l[2 * p].s = sn[p][0];
      l[2 * p + 1].s = sn[p][1];
    }
  }

  std::vector<Line> lines_;
  double phi_ = 0, drive_ = 0;
};

// Recursive quadrature oscillator (no sin() per step); renormalised on demand.
struct Oscillator {
  double c = 1, s = 0, rc = 1, rs = 0;
  void set(double f_hz, double rate_hz, double phase) {
    const double w = 2 * std::numbers::pi * f_hz / rate_hz;
    rc = std::cos(w);
    rs = std::sin(w);
    c = std::cos(phase);
    s = std::sin(phase);
  }
  void step() {
    const double nc = c * rc - s * rs;
    s = s * rc + c * rs;
    c = nc;
  }
  void renormalise() {
    const double k = 1.5 - 0.5 * (c * c + s * s);
    c *= k;
    s *= k;
  }
};

}  // namespace rig::plant::noise
