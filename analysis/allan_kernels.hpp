// Internal: the Allan engine's arithmetic kernels, sums of squared differences over
// contiguous windows w[k] = &P[base + k m] of the phase P (allan_engine.hpp). Each is
// compiled for AVX-512, AVX2 and baseline (target_clones) and picked at load time; they
// know nothing of rings, chunks or threads (allan_stream.cpp schedules them).
#pragma once
#include <cstddef>

namespace rig::analysis::detail::kernels {

// sum over t < len of (w2 - 2 w1 + w0)^2: one OADEV/ADEV/TOTDEV tau (NIST SP 1065 eq. 11).
double sum_d2(const double* w0, const double* w1, const double* w2, std::size_t len);

// sum over t < len of (w3 - 3 w2 + 3 w1 - w0)^2: one HDEV/OHDEV tau (SP 1065 eq. 17).
double sum_d3(const double* w0, const double* w1, const double* w2, const double* w3, std::size_t len);

// The non-overlapped ADEV/HDEV terms (SP 1065 eq. 10, 17): only every stride-th t, from t = first
// while t < len; four independent accumulators (the terms are sparse: a vector load would waste
// most of its lanes, but one chain of dependent additions is what bounded the scalar loop).
double sum_d2_strided(const double* w0, const double* w1, const double* w2, std::size_t first, std::size_t stride,
                      std::size_t len);
double sum_d3_strided(const double* w0, const double* w1, const double* w2, const double* w3, std::size_t first,
                      std::size_t stride, std::size_t len);

// A doubling chain m, 2m, .., 2^(k-1) m of OADEV/TOTDEV taus aligned at a common head h (the
// newest phase point of each term): tau 2^i m's term is P[h] - 2 P[h - 2^i m] + P[h - 2^(i+1) m],
// so k taus need k + 2 streams, not 3k: the loads that bound sum_d2 are shared.
// lag[j] = &P[h0 - 2^j m], j = 0..k; out[i] += sum of squared terms of tau 2^i m. k <= kMaxChain.
inline constexpr int kMaxChain = 8;
void chain_d2(int k, const double* head, const double* const* lag, std::size_t len, double* out);

// The same for OHDEV (SP 1065 eq. 18): tau 2^i m's term is P[h] - 3 P[h - 2^i m] + 3 P[h - 2^(i+1) m]
// - P[h - 3 2^i m]; lag2[j] = &P[h0 - 2^j m], j = 0..k, lag3[i] = &P[h0 - 3 2^i m], i < k:
// 2k + 2 streams instead of 4k.
void chain_d3(int k, const double* head, const double* const* lag2, const double* const* lag3, std::size_t len,
              double* out);

// MDEV/TDEV (SP 1065 eq. 14): the m-window sum of second differences `inner` slides by one
// base per point; its increment is the third difference w3 - 3 w2 + 3 w1 - w0. Returns the sum
// of the squared window sums after each step and leaves `inner` at the last one. m: the
// windows' spacing (w1 = w0 + m, ...), for the direct sums `inner` is taken again from.
double mdev_run(const double* w0, const double* w1, const double* w2, const double* w3, std::size_t len, std::size_t m,
                double& inner);

// sum over t < len of (w2 - 2 w1 + w0): MDEV's window sum at one base, computed directly.
double sum_second_diff(const double* w0, const double* w1, const double* w2, std::size_t len);

// TOTDEV's reflected edge terms (SP 1065 eq. 25), r read backwards (r[len - 1 - t]):
// left  sum of ((k - r) - 2 c + f)^2, k = 2 P[0];
// right sum of ((f - 2 c) + k - r)^2, k = 2 P[N-1]  (each term as the scalar code wrote it).
double sum_reflected_left(double k, const double* r, const double* c, const double* f, std::size_t len);
double sum_reflected_right(double k, const double* r, const double* c, const double* f, std::size_t len);

}  // namespace rig::analysis::detail::kernels
