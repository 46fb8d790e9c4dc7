// The Allan engine's kernels (see allan_kernels.hpp). Four or more independent vector
// accumulators per reduction, so a sum is not one long FMA dependency chain.
#include "analysis/allan_kernels.hpp"

#include <algorithm>

#include "analysis/clones.hpp"

namespace rig::analysis::detail::kernels {

namespace {

// Four independent vector accumulators: the sum is not one long FMA dependency chain.
using v8 = double __attribute__((vector_size(64)));
#if defined(__clang__)
// clang (the fuzz build) refuses any call that passes or returns a 64-byte vector without
// AVX-512 (the ABI would change), inlined or not: there the helpers are expressions. GCC, which
// builds the rig, keeps the functions.
// The load is a memcpy (the data are 8-byte aligned): clang keeps a 64-byte vector type's
// alignment through an aligned(8) alias, which UBSan's alignment check then reports.
#define load8(p)                             \
  __extension__({                            \
    v8 lv_;                                  \
    __builtin_memcpy(&lv_, (p), sizeof lv_); \
    lv_;                                     \
  })
#define hsum(v)                                       \
  __extension__({                                     \
    const v8 hv_ = (v);                               \
    double hs_ = 0;                                   \
    for (int hi_ = 0; hi_ < 8; ++hi_) hs_ += hv_[hi_]; \
    hs_;                                              \
  })
#else
inline v8 load8(const double* p) {
  v8 v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
inline double hsum(v8 v) {
  double s = 0;
  for (int i = 0; i < 8; ++i) s += v[i];
  return s;
}
#endif

}  // namespace

RIG_CLONES double sum_d2(const double* w0, const double* w1, const double* w2, std::size_t len) {
  v8 a0{}, a1{}, a2{}, a3{};
  std::size_t t = 0;
  for (; t + 32 <= len; t += 32) {
    const v8 d0 = load8(w2 + t) - 2 * load8(w1 + t) + load8(w0 + t);
    const v8 d1 = load8(w2 + t + 8) - 2 * load8(w1 + t + 8) + load8(w0 + t + 8);
    const v8 d2 = load8(w2 + t + 16) - 2 * load8(w1 + t + 16) + load8(w0 + t + 16);
    const v8 d3 = load8(w2 + t + 24) - 2 * load8(w1 + t + 24) + load8(w0 + t + 24);
    a0 += d0 * d0, a1 += d1 * d1, a2 += d2 * d2, a3 += d3 * d3;
  }
  double s = hsum((a0 + a1) + (a2 + a3));
  for (; t < len; ++t) {
    const double d = w2[t] - 2 * w1[t] + w0[t];
    s += d * d;
  }
  return s;
}

RIG_CLONES double sum_d3(const double* w0, const double* w1, const double* w2, const double* w3, std::size_t len) {
  v8 a0{}, a1{};
  std::size_t t = 0;
  for (; t + 16 <= len; t += 16) {
    const v8 d0 = load8(w3 + t) - 3 * load8(w2 + t) + 3 * load8(w1 + t) - load8(w0 + t);
    const v8 d1 = load8(w3 + t + 8) - 3 * load8(w2 + t + 8) + 3 * load8(w1 + t + 8) - load8(w0 + t + 8);
    a0 += d0 * d0, a1 += d1 * d1;
  }
  double s = hsum(a0 + a1);
  for (; t < len; ++t) {
    const double d = w3[t] - 3 * w2[t] + 3 * w1[t] - w0[t];
    s += d * d;
  }
  return s;
}

double sum_d2_strided(const double* w0, const double* w1, const double* w2, std::size_t first, std::size_t stride,
                      std::size_t len) {
  double a[4] = {};
  std::size_t t = first;
  for (; t + 3 * stride < len; t += 4 * stride)
    for (std::size_t l = 0; l < 4; ++l) {
      const std::size_t u = t + l * stride;
      const double d = w2[u] - 2 * w1[u] + w0[u];
      a[l] += d * d;
    }
  for (std::size_t l = 0; t < len; t += stride, ++l) {
    const double d = w2[t] - 2 * w1[t] + w0[t];
    a[l] += d * d;
  }
  return (a[0] + a[1]) + (a[2] + a[3]);
}

namespace {

// sum_d3_strided when the windows are one series (w_k = w0 + k stride: the ring does not wrap
// between them, always so in memory): term j's four points are D[j..j+3] of D[i] = w0[first +
// i stride], so each term loads one new point and keeps three in registers (the general loop
// loads four, three of them loaded by the term before). The same terms in the same
// accumulators (term j in a[j % 4]) as the general loop: the same sum, bit for bit.
double sum_d3_series(const double* w0, std::size_t first, std::size_t stride, std::size_t len) {
  double a[4] = {};
  const double* p = w0 + first;
  const std::size_t terms = (len - first + stride - 1) / stride;
  double d0 = p[0], d1 = p[stride], d2 = p[2 * stride];
  const auto term = [&](double& acc, std::size_t j) {
    const double d3 = p[(j + 3) * stride];
    const double d = d3 - 3 * d2 + 3 * d1 - d0;
    acc += d * d;
    d0 = d1, d1 = d2, d2 = d3;
  };
  std::size_t j = 0;
  for (; j + 4 <= terms; j += 4) term(a[0], j), term(a[1], j + 1), term(a[2], j + 2), term(a[3], j + 3);
  for (std::size_t l = 0; j < terms; ++j, ++l) term(a[l], j);
  return (a[0] + a[1]) + (a[2] + a[3]);
}

}  // namespace

double sum_d3_strided(const double* w0, const double* w1, const double* w2, const double* w3, std::size_t first,
                      std::size_t stride, std::size_t len) {
  if (first < len && w1 == w0 + stride && w2 == w1 + stride && w3 == w2 + stride)
    return sum_d3_series(w0, first, stride, len);
  double a[4] = {};
  std::size_t t = first;
  for (; t + 3 * stride < len; t += 4 * stride)
    for (std::size_t l = 0; l < 4; ++l) {
      const std::size_t u = t + l * stride;
      const double d = w3[u] - 3 * w2[u] + 3 * w1[u] - w0[u];
      a[l] += d * d;
    }
  for (std::size_t l = 0; t < len; t += stride, ++l) {
    const double d = w3[t] - 3 * w2[t] + 3 * w1[t] - w0[t];
    a[l] += d * d;
  }
  return (a[0] + a[1]) + (a[2] + a[3]);
}

namespace {

// A doubling chain m, 2m, .., 2^(K-1) m of OADEV/TOTDEV taus aligned at a common head h (the
// newest phase point of each term): tau 2^i m's term is P[h] - 2 P[h - 2^i m] + P[h - 2^(i+1) m],
// so K taus need K + 2 streams, not 3K: the loads that bound sum_d2 are shared.
// lag[j] = &P[h0 - 2^j m], j = 0..K; out[i] += sum of squared terms of tau 2^i m.
template <int K>
[[gnu::always_inline]] inline void chain_d2_body(const double* head, const double* const* lag, std::size_t len,
                                                 double* out) {
  v8 a[K][2] = {};
  std::size_t t = 0;
  for (; t + 16 <= len; t += 16) {
    const v8 h0 = load8(head + t), h1 = load8(head + t + 8);
    v8 p0 = load8(lag[0] + t), p1 = load8(lag[0] + t + 8);
#pragma GCC unroll 8
    for (int i = 0; i < K; ++i) {
      const v8 q0 = load8(lag[i + 1] + t), q1 = load8(lag[i + 1] + t + 8);
      const v8 d0 = h0 - 2 * p0 + q0, d1 = h1 - 2 * p1 + q1;
      a[i][0] += d0 * d0;
      a[i][1] += d1 * d1;
      p0 = q0, p1 = q1;
    }
  }
  for (int i = 0; i < K; ++i) {
    double s = hsum(a[i][0] + a[i][1]);
    for (std::size_t u = t; u < len; ++u) {
      const double d = head[u] - 2 * lag[i][u] + lag[i + 1][u];
      s += d * d;
    }
    out[i] += s;
  }
}

#define RIG_CHAIN(K)                                                                                 \
  RIG_CLONES void chain_d2_##K(const double* head, const double* const* lag, std::size_t len, double* out) { \
    chain_d2_body<K>(head, lag, len, out);                                                           \
  }
RIG_CHAIN(2)
RIG_CHAIN(3)
RIG_CHAIN(4)
RIG_CHAIN(5)
RIG_CHAIN(6)
RIG_CHAIN(7)
RIG_CHAIN(8)
#undef RIG_CHAIN
}  // namespace

void chain_d2(int k, const double* head, const double* const* lag, std::size_t len, double* out) {
  switch (k) {
    case 2: return chain_d2_2(head, lag, len, out);
    case 3: return chain_d2_3(head, lag, len, out);
    case 4: return chain_d2_4(head, lag, len, out);
    case 5: return chain_d2_5(head, lag, len, out);
    case 6: return chain_d2_6(head, lag, len, out);
    case 7: return chain_d2_7(head, lag, len, out);
    case 8: return chain_d2_8(head, lag, len, out);
    default: break;
  }
  for (int i = 0; i < k; ++i) out[i] += sum_d2(lag[i + 1], lag[i], head, len);
}

namespace {

// The Hadamard twin of chain_d2_body: tau 2^i m's term is P[h] - 3 P[h - 2^i m] + 3 P[h - 2^(i+1) m]
// - P[h - 3 2^i m] (SP 1065 eq. 18); lag2[j] = &P[h0 - 2^j m], j = 0..K, lag3[i] = &P[h0 - 3 2^i m]:
// K taus from 2K + 2 streams instead of 4K. Each term as sum_d3 writes it.
template <int K>
[[gnu::always_inline]] inline void chain_d3_body(const double* head, const double* const* lag2,
                                                 const double* const* lag3, std::size_t len, double* out) {
  v8 a[K][2] = {};
  std::size_t t = 0;
  for (; t + 16 <= len; t += 16) {
    const v8 h0 = load8(head + t), h1 = load8(head + t + 8);
    v8 p0 = load8(lag2[0] + t), p1 = load8(lag2[0] + t + 8);
#pragma GCC unroll 8
    for (int i = 0; i < K; ++i) {
      const v8 q0 = load8(lag2[i + 1] + t), q1 = load8(lag2[i + 1] + t + 8);
      const v8 d0 = h0 - 3 * p0 + 3 * q0 - load8(lag3[i] + t);
      const v8 d1 = h1 - 3 * p1 + 3 * q1 - load8(lag3[i] + t + 8);
      a[i][0] += d0 * d0;
      a[i][1] += d1 * d1;
      p0 = q0, p1 = q1;
    }
  }
  for (int i = 0; i < K; ++i) {
    double s = hsum(a[i][0] + a[i][1]);
    for (std::size_t u = t; u < len; ++u) {
      const double d = head[u] - 3 * lag2[i][u] + 3 * lag2[i + 1][u] - lag3[i][u];
      s += d * d;
    }
    out[i] += s;
  }
}

#define RIG_CHAIN3(K)                                                                                     \
  RIG_CLONES void chain_d3_##K(const double* head, const double* const* lag2, const double* const* lag3, \
                               std::size_t len, double* out) {                                           \
    chain_d3_body<K>(head, lag2, lag3, len, out);                                                         \
  }
RIG_CHAIN3(2)
RIG_CHAIN3(3)
RIG_CHAIN3(4)
RIG_CHAIN3(5)
RIG_CHAIN3(6)
RIG_CHAIN3(7)
RIG_CHAIN3(8)
#undef RIG_CHAIN3

}  // namespace

void chain_d3(int k, const double* head, const double* const* lag2, const double* const* lag3, std::size_t len,
              double* out) {
  switch (k) {
    case 2: return chain_d3_2(head, lag2, lag3, len, out);
    case 3: return chain_d3_3(head, lag2, lag3, len, out);
    case 4: return chain_d3_4(head, lag2, lag3, len, out);
    case 5: return chain_d3_5(head, lag2, lag3, len, out);
    case 6: return chain_d3_6(head, lag2, lag3, len, out);
    case 7: return chain_d3_7(head, lag2, lag3, len, out);
    case 8: return chain_d3_8(head, lag2, lag3, len, out);
    default: break;
  }
  for (int i = 0; i < k; ++i) out[i] += sum_d3(lag3[i], lag2[i + 1], lag2[i], head, len);
}

namespace {

// Inclusive prefix sum of one vector: three shift-and-add steps (Hillis-Steele).
#if defined(__clang__)
#define scan8(x_in)                                                              \
  __extension__({                                                                \
    v8 sx_ = (x_in);                                                             \
    const v8 sz_{};                                                              \
    sx_ += __builtin_shufflevector(sz_, sx_, 0, 8, 9, 10, 11, 12, 13, 14);       \
    sx_ += __builtin_shufflevector(sz_, sx_, 0, 1, 8, 9, 10, 11, 12, 13);        \
    sx_ += __builtin_shufflevector(sz_, sx_, 0, 1, 2, 3, 8, 9, 10, 11);          \
    sx_;                                                                         \
  })
#else
using m8 = long long __attribute__((vector_size(64)));
inline v8 scan8(v8 x) {
  const v8 z{};
  x += __builtin_shuffle(z, x, m8{0, 8, 9, 10, 11, 12, 13, 14});
  x += __builtin_shuffle(z, x, m8{0, 1, 8, 9, 10, 11, 12, 13});
  x += __builtin_shuffle(z, x, m8{0, 1, 2, 3, 8, 9, 10, 11});
  return x;
}
#endif

}  // namespace

namespace {

// One tile of kFusedParts x part_len points, fused: the third differences, their running sum
// (a vector scan per 8 points, the parts interleaved so no single carry chain bounds it) and the
// sums of the running sums and of their squares stay in registers. With c the part's local
// running sum and off the window sum before the part, sum (off + c)^2 = S2 + 2 off S1 + n off^2.
constexpr std::size_t kFusedParts = 4;
constexpr std::size_t kDirectMdevM = 8;
RIG_CLONES void mdev_tile(const double* w0, const double* w1, const double* w2, const double* w3,
                          std::size_t part_len, double* s1_out, double* s2_out, double* tot_out) {
  v8 carry[kFusedParts] = {}, s1[kFusedParts] = {}, s2[kFusedParts] = {};
  for (std::size_t r = 0; r < part_len; r += 8)
    for (std::size_t j = 0; j < kFusedParts; ++j) {
      const std::size_t b = j * part_len + r;
      const v8 d = load8(w3 + b) - 3 * load8(w2 + b) + 3 * load8(w1 + b) - load8(w0 + b);
      const v8 c = scan8(d) + carry[j];
      carry[j] = v8{} + c[7];
      s1[j] += c;
      s2[j] += c * c;
    }
  for (std::size_t j = 0; j < kFusedParts; ++j) {
    s1_out[j] = hsum(s1[j]);
    s2_out[j] = hsum(s2[j]);
    tot_out[j] = carry[j][0];
  }
}

}  // namespace

// sum over t < len of (sum over i = 1..m of D(t + i))^2, D(j) = w2[j] - 2 w1[j] + w0[j]: MDEV's
// window sums taken each on its own (reads w_k[1 .. len + m - 1]).
RIG_CLONES double sum_window_sums_sq(const double* w0, const double* w1, const double* w2, std::size_t len,
                                     std::size_t m) {
  v8 a0{}, a1{};
  std::size_t t = 0;
  for (; t + 16 <= len; t += 16) {
    v8 s0{}, s1{};
    for (std::size_t i = 1; i <= m; ++i) {
      s0 += load8(w2 + t + i) - 2 * load8(w1 + t + i) + load8(w0 + t + i);
      s1 += load8(w2 + t + i + 8) - 2 * load8(w1 + t + i + 8) + load8(w0 + t + i + 8);
    }
    a0 += s0 * s0, a1 += s1 * s1;
  }
  double s = hsum(a0 + a1);
  for (; t < len; ++t) {
    double w = 0;
    for (std::size_t i = 1; i <= m; ++i) w += w2[t + i] - 2 * w1[t + i] + w0[t + i];
    s += w * w;
  }
  return s;
}

double mdev_run(const double* w0, const double* w1, const double* w2, const double* w3, std::size_t len, std::size_t m,
                double& inner) {
  // Up to m = kDirectMdevM each window sum is taken on its own, as OADEV's terms are: rounding
  // then stays one term's, where sliding adds every slide's (below). Its last m terms need points
  // past the windows' len, so they slide from the last one taken.
  if (m >= 1 && m <= kDirectMdevM && len > m) {
    const std::size_t direct = len - m;  // terms t < direct read w_k[t + m] with t + m < len
    const double s = sum_window_sums_sq(w0, w1, w2, direct, m);
    inner = sum_second_diff(w0 + direct, w1 + direct, w2 + direct, m);  // S at base `direct`
    double tail = 0;
    for (std::size_t t = direct; t < len; ++t) {
      inner += w3[t] - 3 * w2[t] + 3 * w1[t] - w0[t];
      tail += inner * inner;
    }
    return s + tail;
  }
  constexpr std::size_t kPart = 256, kTile = kFusedParts * kPart;
  // The window sum slides by third differences of the phase, each rounded at the phase's own
  // magnitude: over a whole chunk those roundings added up (a rate ramp's phase, a quadratic,
  // read MDEV 5e-6 high at m = 1, where OADEV's direct second differences were exact; a review).
  // So `inner` is taken again directly (sum_second_diff, m terms) at a part's start every
  // `every` parts: every part up to m = 16 (at most 5 % more loads), rarer beyond, so that no
  // more than about 16 m slides run between two direct sums. Only where the m terms lie within
  // the windows' len points (the windows need not be one array: allan_stream.cpp's cursors).
  const std::size_t every = std::max<std::size_t>(1, (16 * m + kPart - 1) / kPart);
  std::size_t part = 0;  // parts since the run's start
  const auto anchor = [&](std::size_t t) {
    if (m > 0 && t + m <= len) inner = sum_second_diff(w0 + t, w1 + t, w2 + t, m);
  };
  double s = 0;
  std::size_t t0 = 0;
  for (; t0 + kTile <= len; t0 += kTile) {
    double s1[kFusedParts], s2[kFusedParts], tot[kFusedParts];
    mdev_tile(w0 + t0, w1 + t0, w2 + t0, w3 + t0, kPart, s1, s2, tot);
    for (std::size_t j = 0; j < kFusedParts; ++j, ++part) {
      if (part % every == 0) anchor(t0 + j * kPart);
      s += s2[j] + 2 * inner * s1[j] + static_cast<double>(kPart) * inner * inner;
      inner += tot[j];
    }
  }
  for (std::size_t k = 0; t0 < len; ++t0, ++k) {  // the last partial tile, point by point
    if (k % kPart == 0 && part++ % every == 0) anchor(t0);
    inner += w3[t0] - 3 * w2[t0] + 3 * w1[t0] - w0[t0];
    s += inner * inner;
  }
  return s;
}

// Four vector accumulators, like sum_d2: the scalar loop it replaces was one chain of dependent
// additions (the compiler may not reassociate them), 12 % of an MDEV run in segment primes.
RIG_CLONES double sum_second_diff(const double* w0, const double* w1, const double* w2, std::size_t len) {
  v8 a0{}, a1{}, a2{}, a3{};
  std::size_t t = 0;
  for (; t + 32 <= len; t += 32) {
    a0 += load8(w2 + t) - 2 * load8(w1 + t) + load8(w0 + t);
    a1 += load8(w2 + t + 8) - 2 * load8(w1 + t + 8) + load8(w0 + t + 8);
    a2 += load8(w2 + t + 16) - 2 * load8(w1 + t + 16) + load8(w0 + t + 16);
    a3 += load8(w2 + t + 24) - 2 * load8(w1 + t + 24) + load8(w0 + t + 24);
  }
  double s = hsum((a0 + a1) + (a2 + a3));
  for (; t < len; ++t) s += w2[t] - 2 * w1[t] + w0[t];
  return s;
}

namespace {

// r[len - 1 - t .. len - 8 - t] as one vector in t order: the eight values below r + len - t,
// lanes reversed.
#if defined(__clang__)
#define load8_reversed(p) __builtin_shufflevector(load8(p), load8(p), 7, 6, 5, 4, 3, 2, 1, 0)
#else
inline v8 load8_reversed(const double* p) { return __builtin_shuffle(load8(p), m8{7, 6, 5, 4, 3, 2, 1, 0}); }
#endif

// TOTDEV's edge terms, k - r[len-1-t] - 2 c[t] + f[t] (left) or f[t] - 2 c[t] + k - r[len-1-t]
// (right, each term as the scalar code writes it), squared and summed. Four vector
// accumulators (lane t % 32, fixed: the same sum on every machine and thread count): one
// accumulator was one chain of dependent FMAs per 8 terms, which bounded this loop (13 % of a
// TOTDEV run, for 7 % of its terms).
template <bool kLeft>
[[gnu::always_inline]] inline double sum_reflected(double k, const double* r, const double* c, const double* f,
                                                   std::size_t len) {
  const v8 kv = v8{} + k;
  v8 acc[4] = {};
  std::size_t t = 0;
  for (; t + 32 <= len; t += 32)
#pragma GCC unroll 4
    for (std::size_t q = 0; q < 4; ++q) {
      const std::size_t u = t + 8 * q;
      const v8 rv = load8_reversed(r + len - 8 - u);
      const v8 d = kLeft ? kv - rv - 2 * load8(c + u) + load8(f + u) : load8(f + u) - 2 * load8(c + u) + kv - rv;
      acc[q] += d * d;
    }
  double s = hsum((acc[0] + acc[1]) + (acc[2] + acc[3]));
  for (; t < len; ++t) {
    const double d = kLeft ? k - r[len - 1 - t] - 2 * c[t] + f[t] : f[t] - 2 * c[t] + k - r[len - 1 - t];
    s += d * d;
  }
  return s;
}

}  // namespace

RIG_CLONES double sum_reflected_left(double k, const double* r, const double* c, const double* f, std::size_t len) {
  return sum_reflected<true>(k, r, c, f, len);
}

RIG_CLONES double sum_reflected_right(double k, const double* r, const double* c, const double* f, std::size_t len) {
  return sum_reflected<false>(k, r, c, f, len);
}

}  // namespace rig::analysis::detail::kernels
