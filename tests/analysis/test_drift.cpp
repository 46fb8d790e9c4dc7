// The record's drift (analysis/drift.hpp) and R read from it (noise_terms): the engine's
// slope from its phase sums equals the direct least-squares slope on every path (in memory on one
// or two threads, streamed, phase data); each noise term's share of the slope's variance matches
// simulated records; a ramp is reported with bounds, a record without one gives R null with an
// upper limit.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "analysis/allan.hpp"
#include "analysis/drift.hpp"
#include "analysis/noise_terms.hpp"
#include "injected_noise.hpp"

namespace rig::analysis {
namespace {

std::vector<double> noisy_ramp(std::size_t n, double slope_per_sample, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<double> y(n);
  double walk = 0;
  for (std::size_t i = 0; i < n; ++i) y[i] = 3.5 + slope_per_sample * static_cast<double>(i) + (walk += 0.01 * g(rng)) + g(rng);
  return y;
}

Drift engine_drift(std::span<const double> data, DataKind kind, double rate, unsigned threads, std::size_t budget,
                   std::size_t chunk = 4096) {
  DevOptions o;
  o.data = kind;
  o.rate_hz = rate;
  o.taus = parse_tau_grid("octave");
  o.threads = threads;
  o.bounds = false;
  StreamOptions so;
  so.memory_budget_bytes = budget;
  so.chunk = chunk;
  Drift d;
  so.drift = &d;
  SpanSource src(data);
  deviation_stream(src, o, so);
  return d;
}

TEST(Drift, LeastSquaresSlopeOfALine) {
  std::vector<double> y(1001);
  for (std::size_t i = 0; i < y.size(); ++i) y[i] = -2.0 + 0.25 * static_cast<double>(i) / 50.0;  // 0.25 per second at 50 Hz
  const Drift d = least_squares_drift(y, 50);
  EXPECT_EQ(d.n, 1001u);
  EXPECT_NEAR(d.slope, 0.25, 1e-14);
  EXPECT_DOUBLE_EQ(d.length_s(), 1001 / 50.0);
  EXPECT_FALSE(least_squares_drift(std::vector<double>{1, 2}, 1).ok());
}

// The engine keeps sum P and P_n over its pass; the slope from them (summation by parts) is the
// direct one to rounding, in memory (one thread, two: the build splits at 0.55 n from 2^20
// points), streamed through a small ring, and for phase data (x = tau0 cumsum y).
TEST(Drift, TheEnginesSlopeIsTheDirectOneOnEveryPath) {
  const double rate = 100;
  const std::vector<double> y = noisy_ramp((1u << 20) + 12345, 2e-6, 7);
  const Drift direct = least_squares_drift(y, rate);
  const double tol = 1e-9 * std::abs(direct.slope);
  const std::size_t all = std::size_t{1} << 40, small = std::size_t{8} << 20;
  for (unsigned th : {1u, 2u}) {
    EXPECT_NEAR(engine_drift(y, DataKind::Frequency, rate, th, all).slope, direct.slope, tol) << th << " thread(s)";
    EXPECT_NEAR(engine_drift(y, DataKind::Frequency, rate, th, small).slope, direct.slope, tol) << "streamed, " << th;
  }
  std::vector<double> x(y.size() + 1, 5.0);  // a phase offset: the engine's P starts from x[0]
  for (std::size_t i = 0; i < y.size(); ++i) x[i + 1] = x[i] + y[i] / rate;
  for (std::size_t budget : {all, small}) {
    const Drift from_phase = engine_drift(x, DataKind::Phase, rate, 2, budget);
    EXPECT_EQ(from_phase.n, y.size());
    EXPECT_NEAR(from_phase.slope, direct.slope, 1e-7 * std::abs(direct.slope)) << budget;  // x's own rounding
  }
  EXPECT_EQ(engine_drift(y, DataKind::Frequency, rate, 2, all).n, y.size());
  // rig analyze's case (in memory, the default chunk): the same bits on one thread and two, whose
  // build splits at a block boundary that is not a chunk boundary.
  const std::size_t dflt = StreamOptions{}.chunk;
  EXPECT_EQ(engine_drift(y, DataKind::Frequency, rate, 1, all, dflt).slope,
            engine_drift(y, DataKind::Frequency, rate, 2, all, dflt).slope);
}

// Each term's share of var(slope) (drift.hpp) against the slopes of 400 simulated records of that
// term alone (injected_noise.hpp; seeds fixed before looking). The variance of 400 slopes scatters
// by sqrt(2/400) = 7 %: the limits are 4 of those. The flicker bank has corners from 1/(1000 T)
// up, a 1/f spectrum to within its ripple.
TEST(Drift, EachTermsShareOfTheSlopesVarianceMatchesSimulatedRecords) {
  const double rate = 10;
  const std::size_t n = 10000;
  struct Case {
    const char* name;
    injected::Terms t;
    int k;
  };
  const Case cases[] = {{"Q", {2e-3, 0, 0, 0, 0}, 0},
                        {"N", {0, 1e-3, 0, 0, 0}, 1},
                        {"B", {0, 0, 1e-3, 0, 0}, 2},
                        {"K", {0, 0, 0, 1e-3, 0}, 3}};
  for (const Case& c : cases) {
    constexpr int kRecords = 400;
    double sum2 = 0;
    for (int i = 0; i < kRecords; ++i) {
      const Drift d = least_squares_drift(injected::generate(c.t, rate, n, 910000 + 1000 * c.k + i), rate);
      sum2 += d.slope * d.slope;
    }
    Drift d;
    d.n = n;
    d.tau0 = 1 / rate;
    const std::array<double, 4> v = drift_variance_terms({c.t.Q, c.t.N, c.t.B, c.t.K}, d);
    const double ratio = sum2 / kRecords / v[static_cast<std::size_t>(c.k)];
    std::printf("%s: mean slope^2 / predicted %.3f\n", c.name, ratio);
    EXPECT_NEAR(ratio, 1, 0.28) << c.name;
  }
}

std::vector<DevPoint> oadev_of(const std::vector<double>& y, double rate) {
  DevOptions o;
  o.rate_hz = rate;
  o.taus = parse_tau_grid("log:100");
  return deviation(y, o);
}

// A ramp over a random walk (the coverage suite's "R 6h" set at its CI rate, one seed): R is the
// drift's magnitude with bounds, its reading in `drift`; the model's own R stays in wls. Without
// the ramp, the drift is within its scatter and R is null with |slope| + t sd as upper limit.
TEST(Drift, RIsReadFromTheDrift) {
  const double rate = 10, T = 6 * 3600;
  const auto n = static_cast<std::size_t>(T * rate);
  const double N = 2.2306e-7 * 60, K = 5.1167e-6 / 60, R = 40 * K / std::sqrt(T);  // the ramp 40x its scatter
  const std::vector<double> y = injected::generate({0, N, 1e-6, K, R}, rate, n, 5150);
  const Drift d = least_squares_drift(y, rate);
  const NoiseTerms t = noise_terms(oadev_of(y, rate), T, kRMinRecordS, d);
  ASSERT_TRUE(t.drift);
  ASSERT_TRUE(t.R.value) << t.R.reason;
  EXPECT_DOUBLE_EQ(*t.R.value, std::abs(d.slope));
  // Within 3 of the random walk's sd(slope) = K sqrt(6 / (5 T)) (2.6 % of R here) of the ramp.
  const double sd_rw = K * std::sqrt(1.2 / T);
  EXPECT_NEAR(*t.R.value, R, 3 * sd_rw);
  EXPECT_LT(*t.R.lo, *t.R.value);
  EXPECT_NEAR(*t.R.hi - *t.R.value, t.drift->quantile * t.drift->sd, 1e-20);
  EXPECT_NE(t.R.reason.find("least-squares drift"), std::string::npos) << t.R.reason;
  EXPECT_NE(t.R.reason.find("shorter than the 50 h"), std::string::npos) << t.R.reason;
  EXPECT_GT(t.drift->quantile, 1.0);  // K estimated: Student's t above the normal's 1
  // The model's scatter of the slope is mostly the random walk's, at the fit's K (read from one
  // record: within a factor 2.5 of the truth's).
  EXPECT_GT(t.drift->sd / sd_rw, 0.4);
  EXPECT_LT(t.drift->sd / sd_rw, 2.5);

  const std::vector<double> flat = injected::generate({0, N, 1e-6, K / 10, 0}, rate, n, 5151);
  const Drift d0 = least_squares_drift(flat, rate);
  const NoiseTerms t0 = noise_terms(oadev_of(flat, rate), T, kRMinRecordS, d0);
  ASSERT_TRUE(t0.drift);
  ASSERT_FALSE(t0.R.value) << t0.R.reason;  // this seed's drift is within its scatter
  EXPECT_LT(std::abs(d0.slope), std::sqrt(2.0) * t0.drift->quantile * t0.drift->sd);
  ASSERT_TRUE(t0.R.hi);
  EXPECT_NEAR(*t0.R.hi, std::abs(d0.slope) + t0.drift->quantile * t0.drift->sd, 1e-20);
  EXPECT_NE(t0.R.reason.find("upper limit R <="), std::string::npos) << t0.R.reason;
  EXPECT_NE(t0.R.reason_without_limit.find("within its scatter"), std::string::npos);
  // Without a drift (the Allan points alone) R is the model's.
  const NoiseTerms alone = noise_terms(oadev_of(y, rate), T);
  EXPECT_FALSE(alone.drift);
  EXPECT_EQ(alone.R.value, alone.wls.R.value);
  EXPECT_EQ(alone.R.hi, alone.wls.R.hi);
}

// The confidence asked for reaches every bound and upper limit (a review: --confidence 0.95 gave
// one-sigma noise-term bounds), while the values and which terms are reported stay the method's.
TEST(Drift, TheConfidenceWidensEveryBoundAndChangesNoValue) {
  const double rate = 10, T = 6 * 3600;
  const auto n = static_cast<std::size_t>(T * rate);
  const double N = 2.2306e-7 * 60, K = 5.1167e-6 / 60, R = 40 * K / std::sqrt(T);
  const std::vector<double> y = injected::generate({0, N, 1e-6, K, R}, rate, n, 5150);
  const Drift d = least_squares_drift(y, rate);
  const auto pts = oadev_of(y, rate);
  const NoiseTerms one = noise_terms(pts, T, kRMinRecordS, d);
  const NoiseTerms wide = noise_terms(pts, T, kRMinRecordS, d, 0.95);
  EXPECT_EQ(one.confidence, kOneSigma);
  EXPECT_EQ(wide.confidence, 0.95);
  int widened = 0;
  for (const auto& [a, b] : {std::pair{&one.Q, &wide.Q}, {&one.N, &wide.N}, {&one.B, &wide.B}, {&one.K, &wide.K},
                             {&one.R, &wide.R}}) {
    EXPECT_EQ(a->value, b->value) << a->reason;  // same bits, same nulls
    ASSERT_EQ(a->hi.has_value(), b->hi.has_value()) << a->reason;
    if (a->hi) {
      EXPECT_GE(*b->hi, *a->hi) << a->reason;
    }
    if (a->lo && b->lo) {
      EXPECT_LE(*b->lo, *a->lo) << a->reason;
    }
    if (a->value && a->lo && a->hi && *b->hi - *b->lo > 1.5 * (*a->hi - *a->lo)) ++widened;
  }
  EXPECT_GE(widened, 2) << "N's and R's 95 % intervals are about twice the one-sigma ones";
  // R from the drift: t at 97.5 % instead of 84.1 %, the support rule unchanged.
  ASSERT_TRUE(one.drift && wide.drift && wide.R.value);
  EXPECT_EQ(one.drift->sd, wide.drift->sd);
  EXPECT_GT(wide.drift->quantile, 1.9 * one.drift->quantile / 1.05);
  EXPECT_NEAR(*wide.R.hi - *wide.R.value, wide.drift->quantile * wide.drift->sd, 1e-20);
  for (std::size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(one.model.in_model[k], wide.model.in_model[k]) << k;
    EXPECT_EQ(one.model.value[k], wide.model.value[k]) << k;
    if (!one.model.in_model[k] && one.model.upper[k] > 0) {
      EXPECT_GT(wide.model.upper[k], one.model.upper[k]) << k;
    }
  }
}

}  // namespace
}  // namespace rig::analysis
