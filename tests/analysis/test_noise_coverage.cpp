// The injected-noise generator gives the IEEE 952 curve it is asked for, and (CI-sized
// coverage suite) the noise-term fit's bounds hold the injected terms at their stated coverage.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "analysis/theo.hpp"
#include "tests/analysis/noise_coverage.hpp"

namespace rig::analysis::injected {

// Mean OADEV^2 over seeds at a few taus against the model: white phase, white rate, flicker,
// random walk and ramp, one at a time (8 seeds, 1e5 samples at 100 Hz).
double mean_avar_ratio(const Terms& t, double tau, int seeds = 8) {
  const double rate = 100;
  const std::size_t n = 100000;
  double s = 0;
  for (int i = 0; i < seeds; ++i) {
    const auto y = generate(t, rate, n, 500 + static_cast<std::uint64_t>(i));
    DevOptions o;
    o.rate_hz = rate;
    o.bounds = false;
    o.factors = {static_cast<std::size_t>(std::lround(tau * rate))};
    const auto d = deviation(y, o);
    s += d[0].dev * d[0].dev / model_avar(t, tau);
  }
  return s / seeds;
}

TEST(InjectedNoise, EachTermGivesItsAllanVariance) {
  EXPECT_NEAR(mean_avar_ratio({1e-6, 0, 0, 0, 0}, 0.1), 1, 0.03);
  EXPECT_NEAR(mean_avar_ratio({0, 1e-5, 0, 0, 0}, 1), 1, 0.03);
  EXPECT_NEAR(mean_avar_ratio({0, 0, 1e-6, 0, 0}, 0.1), 1, 0.05);
  EXPECT_NEAR(mean_avar_ratio({0, 0, 1e-6, 0, 0}, 10), 1, 0.10);
  EXPECT_NEAR(mean_avar_ratio({0, 0, 0, 1e-7, 0}, 1), 1, 0.05);
  EXPECT_NEAR(mean_avar_ratio({0, 0, 0, 0, 1e-8}, 10, 1), 1, 1e-6);  // deterministic
  // and at T/4 (the longest tau the fit uses, where R dominates on the 6 h and 60 h sets)
  EXPECT_NEAR(mean_avar_ratio({0, 0, 0, 0, 1e-8}, 249.9, 1), 1, 1e-6);
}

// The ramp's scatter (noise_model.hpp term_scatter): a deterministic ramp over a random walk
// scatters the Allan variance only by their cross term, far less than a random walk of the same
// size would. 400 records of K + R (10 Hz, 6 h, R 75 % and 84 % of sigma^2 at T/8 and T/4): the
// measured variance of s / mu is within 25 % of 2/model_edf (measured 0.217 vs 0.207, 0.368 vs
// 0.327) and below 0.75 of what random walk's EDF, the previous rule for R, gives (0.339, 0.895).
// Theo1 at T/2 and 0.75 T (analysis/long_tau_fit.hpp) against the model's expectation for it,
// each term alone: mean over `seeds` records of n samples at 100 Hz of Theo1 / (AVAR_k(tau)
// factor_k), point q.
double mean_theo1_ratio(const Terms& t, int k, std::size_t q, int seeds, std::size_t n) {
  const double rate = 100;
  double s = 0;
  for (int i = 0; i < seeds; ++i) {
    const auto y = generate(t, rate, n, 900 + static_cast<std::uint64_t>(i));
    const auto pts = theo1_fit_points(y, DataKind::Frequency, rate);
    if (pts.size() != 2) return 0;
    s += pts[q].var / (term_avar(t, k, pts[q].tau_s) * pts[q].factor[static_cast<std::size_t>(k)]);
  }
  return s / seeds;
}

// The estimator: Theo1 (SP 1065 eq. 30) of the phase every stride-th sample. With stride 1 it is
// the rig's Theo1 (exact against NBS14 and Stable32, test_theo.cpp) to rounding; with a stride it
// is exactly Theo1 of the phase sampled at stride tau0 (built here independently).
TEST(LongTauFit, Theo1PointsAreTheo1OfThePhaseOnTheirGrid) {
  for (const std::size_t n : {999u, 20000u}) {
    const auto y = generate({0, 1e-5, 0, 1e-6, 0}, 100, n, 77);
    const auto pts = theo1_fit_points(y, DataKind::Frequency, 100);
    ASSERT_EQ(pts.size(), 2u);
    for (const LongTauFitPoint& p : pts) {
      EXPECT_EQ(p.m % (2 * p.stride), 0u);
      EXPECT_NEAR(p.tau_s / (p.frac * static_cast<double>(n) / 100), 1, 0.01) << n;
      if (p.stride == 1) {
        LongTauOptions o;
        o.type = LongTau::Theo1;
        o.rate_hz = 100;
        o.bounds = false;
        o.factors = {p.m};
        const auto d = long_tau(y, o);
        ASSERT_EQ(d.size(), 1u);
        EXPECT_NEAR(p.var / (d[0].dev * d[0].dev), 1, 1e-9) << n;
      } else {
        std::vector<double> X(1, 0.0);
        long double acc = 0;
        for (std::size_t i = 0; i < n; ++i) {
          acc += y[i] - y[0];
          if ((i + 1) % p.stride == 0) X.push_back(static_cast<double>(acc) / 100);
        }
        EXPECT_NEAR(p.var / theo1_var(X, p.m / p.stride, static_cast<double>(p.stride) / 100).var, 1, 1e-9) << n;
      }
    }
  }
}

// The expectation factors: white FM is unbiased (Howe & Tasset: Theo1 matches AVAR at
// tau = 0.75 m for white FM); the ramp (x = t^2, every bracket 2 k (m - k)) against its
// continuous limit (4/(0.75 m^2)) m^4 int_0^1/2 u (1-u)^2 du / (2 (0.75 m)^2) = 0.2716; white PM
// ~ ln(m/2) (sum_k 4/k); none depends on the grid's stride (stationary increments).
TEST(LongTauFit, Theo1FactorsAgainstClosedForms) {
  const auto f = theo1_factors(2048, 1366, 1);
  EXPECT_NEAR(f[1], 1, 1e-9);
  EXPECT_NEAR(f[4], 0.2716, 1e-3);
  EXPECT_NEAR(f[0] / std::log(1366.0 / 2), 1, 0.1);
  const auto g = theo1_factors(2048, 1366, 64);
  for (std::size_t k = 0; k < 5; ++k) EXPECT_NEAR(g[k] / f[k], 1, 1e-6) << k;
}

// Each term alone through the generator: the mean Theo1 over 400 records of 4000 samples is the
// model's expectation (basis times factor). The log-scale variance of a point is 0.2-3.4
// (long_tau_fit.cpp), so the mean of 400 ratios has a relative sd of 3-10 %; the ramp is exact.
TEST(InjectedNoise, EachTermGivesItsTheo1) {
  EXPECT_NEAR(mean_theo1_ratio({1e-6, 0, 0, 0, 0}, 0, 0, 400, 4000), 1, 0.1);
  EXPECT_NEAR(mean_theo1_ratio({0, 1e-5, 0, 0, 0}, 1, 0, 400, 4000), 1, 0.15);
  EXPECT_NEAR(mean_theo1_ratio({0, 0, 1e-6, 0, 0}, 2, 0, 400, 4000), 1, 0.2);
  EXPECT_NEAR(mean_theo1_ratio({0, 0, 0, 1e-7, 0}, 3, 0, 400, 4000), 1, 0.25);
  EXPECT_NEAR(mean_theo1_ratio({0, 1e-5, 0, 0, 0}, 1, 1, 400, 4000), 1, 0.2);
  EXPECT_NEAR(mean_theo1_ratio({0, 0, 0, 1e-7, 0}, 3, 1, 400, 4000), 1, 0.3);
  EXPECT_NEAR(mean_theo1_ratio({0, 0, 0, 0, 1e-8}, 4, 0, 1, 4000), 1, 1e-6);
  EXPECT_NEAR(mean_theo1_ratio({0, 0, 0, 0, 1e-8}, 4, 1, 1, 4000), 1, 1e-6);
}

TEST(InjectedNoise, RampScatterIsItsCrossTermWithTheRandomWalk) {
  const Terms t{0, 0, 0, 8.53e-8, 2.2e-9};
  const double rate = 10;
  const std::size_t n = 216000;
  const std::vector<std::size_t> ms{27000, 53999};
  std::vector<double> sum(ms.size()), sum2(ms.size());
  const int seeds = 400;
  for (int i = 0; i < seeds; ++i) {
    const auto y = generate(t, rate, n, 777 + static_cast<std::uint64_t>(i));
    DevOptions o;
    o.rate_hz = rate;
    o.bounds = false;
    o.factors = ms;
    const auto d = deviation(y, o);
    for (std::size_t j = 0; j < ms.size(); ++j) {
      const double q = d[j].dev * d[j].dev / model_avar(t, d[j].tau_s);
      sum[j] += q, sum2[j] += q * q;
    }
  }
  for (std::size_t j = 0; j < ms.size(); ++j) {
    const double tau = static_cast<double>(ms[j]) / rate, mean = sum[j] / seeds, var = sum2[j] / seeds - mean * mean;
    std::array<double, 5> mu{};
    for (int k = 0; k < 5; ++k) mu[static_cast<std::size_t>(k)] = term_avar(t, k, tau);
    const double nu = model_edf(mu, ms[j], n + 1);
    std::array<double, 5> rw = mu;  // the ramp's share given random walk's scatter instead
    rw[3] += rw[4], rw[4] = 0;
    const double nu_rw = model_edf(rw, ms[j], n + 1);
    SCOPED_TRACE("m = " + std::to_string(ms[j]));
    EXPECT_NEAR(mean, 1, 0.1);
    EXPECT_NEAR(var / (2 / nu), 1, 0.25) << "var " << var << ", 2/nu " << 2 / nu;
    std::printf("m %zu: var(s/mu) %.3f, 2/nu %.3f, 2/nu(random walk) %.3f\n", ms[j], var, 2 / nu, 2 / nu_rw);
    EXPECT_LT(var, 0.75 * 2 / nu_rw) << "random walk's EDF " << nu_rw;
  }
}

TEST(NoiseCoverage, CiSized) {
  // 20 seeds per set (issue 12's acceptance), the same seeds as docs/analysis.md's CI-rate table.
  constexpr int kSeeds = 20;
  constexpr int kMaxOff3 = 4;
  const auto cells = run_coverage(sets(true), kSeeds, 12000);
  std::printf("%s", coverage_table(cells).c_str());
  // Pooled over the terms of the one model (Q, N, B(model), K, R; the paper's B is the
  // passport's and judged on its own): the stated 68.3 % bounds of dominant terms hold the
  // truth within +-10 points of 68.3 % (issue 12; 14 dominant cells x 20 runs: about +-3 points
  // of sampling scatter; measured 72.5 %, 74.3 % over 60 seeds per set); a term that never
  // dominates comes back null or with an upper limit (the upper end of the two-sided 68.3 %
  // interval, 84 % one-sided) that holds it in at least 74 % (measured 96 %); a value more than
  // 3x off the truth with bounds excluding it at most kMaxOff3 times in the suite (measured 4
  // with the bounds held over every plausible model, 6 before: mostly a 3e-7 g flicker under K
  // read as B 5-7x where B + R fits best; the acceptance target is none and is not met at these
  // rates: docs/analysis.md).
  int dom = 0, dom_cov = 0, nd = 0, nd_ok = 0, off3 = 0;
  for (const Cell& c : cells) {
    EXPECT_EQ(c.runs, kSeeds);
    if (c.term == "B") continue;
    off3 += c.excluded_3x;
    if (!c.injected) continue;
    if (c.dominant) dom += c.runs, dom_cov += c.covered;
    else nd += c.runs, nd_ok += c.upper_holds;
  }
  const double cov = static_cast<double>(dom_cov) / dom, nd_frac = static_cast<double>(nd_ok) / nd;
  std::printf("dominant: bounds hold %d/%d (%.1f %%); non-dominant: upper limit holds %d/%d; > 3x excluded: %d\n",
              dom_cov, dom, 100 * cov, nd_ok, nd, off3);
  EXPECT_GE(cov, kOneSigma - 0.10);
  EXPECT_LE(cov, kOneSigma + 0.10);
  EXPECT_GE(nd_frac, 0.74);
  EXPECT_LE(off3, kMaxOff3);
  // R dominant on 6 h (from 1000 s to T/4): its bounds hold the truth in at least 8 of 20 (a
  // calibrated 68.3 % cell falls below that with probability 0.2 %) and the median value is
  // within 1.4x of it. The previous fit (R given random walk's EDF, values from the AICc model)
  // held it in 2-3 of 20 with a median of 1.6x.
  for (const Cell& c : cells)
    if (c.set == "R 6h" && c.term == "R") {
      EXPECT_GE(c.covered, 8) << "R on 6 h covered " << c.covered << "/" << c.runs;
      EXPECT_LE(median(c.ratios), 1.4);
    }
}

}  // namespace rig::analysis::injected
