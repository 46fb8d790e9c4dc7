// The injected-noise generator gives the IEEE 952 curve it is asked for, and (CI-sized
// coverage suite) the noise-term fit's bounds hold the injected terms at their stated coverage.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>

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
  // Flicker at the first taus too (the bank's means over each sample and the processes above the
  // Nyquist frequency; the point-sampled bank stopping at rate/4 read +3.8 % at tau0 and -5 % at
  // 2-4 tau0, 20-30 times the standard error of 8 records' mean there)
  for (const double tau : {0.01, 0.02, 0.04})
    EXPECT_NEAR(mean_avar_ratio({0, 0, 1e-6, 0, 0}, tau), 1, 0.01) << "tau " << tau;
  EXPECT_NEAR(mean_avar_ratio({0, 0, 1e-6, 0, 0}, 0.1), 1, 0.02);
  EXPECT_NEAR(mean_avar_ratio({0, 0, 1e-6, 0, 0}, 10), 1, 0.10);
  EXPECT_NEAR(mean_avar_ratio({0, 0, 0, 1e-7, 0}, 1), 1, 0.05);
  EXPECT_NEAR(mean_avar_ratio({0, 0, 0, 0, 1e-8}, 10, 1), 1, 1e-6);  // deterministic
  // and at T/4 (the longest tau the fit uses, where R dominates on the 6 h and 60 h sets)
  EXPECT_NEAR(mean_avar_ratio({0, 0, 0, 0, 1e-8}, 249.9, 1), 1, 1e-6);
}

// The flicker bank's own expected Allan variance (no simulation: each process's, plus the white
// tail's) is the nominal (2 ln2/pi) B^2 from tau0 to 256 tau0 and near it at T/4, at three rates:
// the bank's extent (30 rate down to 1/(1000 T)) and its tail are enough. Stopping the bank at
// rate/4 gives 0.41 at tau0 and 0.93 at 16 tau0 (means, not point samples); leaving out the tail
// 0.995 at tau0.
TEST(InjectedNoise, TheFlickerBanksExpectedAllanVarianceIsTheNominal) {
  for (const double rate : {10.0, 100.0, 1000.0}) {
    const double T = 3600, nominal = term_avar({0, 0, 1e-6, 0, 0}, 2, 1.0);
    const FlickerBank bank = flicker_bank(1e-6, rate, T);
    for (std::size_t m = 1; m <= 256; m *= 2)
      EXPECT_NEAR(flicker_bank_avar(bank, rate, m) / nominal, 1, 1e-4) << rate << " Hz, m " << m;
    const auto quarter = static_cast<std::size_t>(T * rate / 4);
    EXPECT_NEAR(flicker_bank_avar(bank, rate, quarter) / nominal, 1, 1e-3) << rate << " Hz, T/4";
  }
}

// The ramp's scatter (noise_model.hpp term_scatter): a deterministic ramp over a random walk
// scatters the Allan variance only by their cross term, far less than a random walk of the same
// size would. 400 records of K + R (10 Hz, 6 h, R 75 % and 84 % of sigma^2 at T/8 and T/4): the
// measured variance of s / mu is within 25 % of 2/model_edf (measured 0.217 vs 0.207, 0.368 vs
// 0.327) and below 0.75 of what random walk's EDF, the previous rule for R, gives (0.339, 0.895).
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
  // of sampling scatter; measured 73.9 %, 73.0 % over 60 seeds per set, 73.6 % over 240 fresh
  // seeds: the generator's exact flicker of 2026-12-04); a term that never dominates comes back
  // null or with an upper limit (the upper end of the two-sided 68.3 % interval, 84 % one-sided)
  // that holds it in at least 74 % (measured 151/160); a value more than 3x off the truth with
  // bounds excluding it at most kMaxOff3 times in the suite (measured 0 here and over 60 seeds
  // per set, but 15 of 3360 over 240: mostly a 3e-7 g flicker under K read as B 5-7x where the
  // random walk came out low; the acceptance target is none and is not met at these rates in
  // general: docs/analysis.md).
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
  // within 1.4x of it. R read from the record's drift (docs/analysis.md (c)): 16 of 20, median
  // 0.91x on these seeds (44/60 over 60; 11 of 20 at 1.25x on the old generator's records); the
  // Allan model's R (now lsq_fit's) held it in 40/60, and an earlier fit (R given random walk's
  // EDF, values from the AICc model) in 2-3 of 20 at 1.6x.
  for (const Cell& c : cells)
    if (c.set == "R 6h" && c.term == "R") {
      EXPECT_GE(c.covered, 8) << "R on 6 h covered " << c.covered << "/" << c.runs;
      EXPECT_LE(median(c.ratios), 1.4);
    }
}

// A metrologist's outside check (session 47): white FM N = 1e-3 and a random walk K = 5.2e-5
// crossing at 33 s, 1000 s at 100 Hz, so the walk dominates only the last octave or two. At the
// default confidence the terms held, at 95 % K did not (83/100 on the reviewer's generator): K is
// null on about one record in five there, and a null's upper limit, linearised at the fit without
// the walk, was below the truth on nearly half of those. The limit now inverts the test of the
// term at each value with the scatter and EDF that value implies (noise_model.cpp,
// inverted_upper), each point's departure measured by the cube root of s/mu (Wilson-Hilferty),
// whose tails are the chi-square's where ln s has a heavy lower one. Seeds 71000..71199 (fixed
// before looking) and 90417..90616 (a review's, fixed before it looked): K's interval (a null's
// [0, upper limit]) held the truth at 95 % in 348/400 with the linearised limit, 363/400 with the
// test on ln s (session 48) and 373/400 (93.3 %) on the cube root (session 50); the nulls' limits
// in 39, 54 and 64 of 71; N 386/400; at the default K 280, 282 then 292/400, N 310/400.
// Asserted: K and N within 10 points of the stated confidence, and at 95 % the nulls' limits
// holding in at least 60 of them (a regression guard between the last two methods' counts; the
// one-sided limit states 97.5 %, and over 1500 records the nulls' limits held 87.8 %:
// docs/analysis.md, "Coverage over injected noise").
TEST(NoiseCoverage, ARandomWalkOnTheLastOctavesHeldAtTheStatedConfidence) {
  const Set set{"N + K over the last octaves", {0, 1e-3, 0, 5.2e-5, 0}, 100, 1000.0 / 3600};
  constexpr int kSeeds = 200;
  for (const double confidence : {kOneSigma, 0.95}) {
    // Held: a reported interval holding the truth (Cell::covered) or a null whose upper limit
    // does (Cell::null_held).
    int held_n = 0, held_k = 0, nulls_k = 0, null_held_k = 0, runs = 0;
    for (const std::uint64_t base : {71000u, 90417u})
      for (const Cell& c : run_coverage({set}, kSeeds, base, false, nullptr, confidence)) {
        if (c.term == "N") held_n += c.covered + c.null_held, runs += c.runs;
        if (c.term == "K") held_k += c.covered + c.null_held, nulls_k += c.null_, null_held_k += c.null_held;
      }
    std::printf("confidence %.4f: N held %d/%d, K held %d/%d (nulls %d, their limit held %d)\n", confidence, held_n,
                runs, held_k, runs, nulls_k, null_held_k);
    ASSERT_EQ(runs, 2 * kSeeds);
    EXPECT_NEAR(static_cast<double>(held_n) / runs, confidence, 0.10) << confidence;
    EXPECT_NEAR(static_cast<double>(held_k) / runs, confidence, 0.10) << confidence;
    if (confidence > 0.9) {
      EXPECT_GE(null_held_k, 60) << "of " << nulls_k;
    }
  }
}

// The paper method's B (sigma(tau_cp)/0.664 off the quartic over the whole log grid) with the
// bounds of what it reads: the quartic's value is a weighted sum of every point, so its scatter
// is the polynomial's (noise_terms.cpp, paper_poly_edf), not one Allan point's. On flicker alone
// (B dominates every tau; 50 Hz, 2000 s) one point's chi-square interval held the truth on 49/100
// (seeds 5000..) and 111/200 (seeds 64000.., fixed before looking), the truth above the upper
// bound in 86 of those 200: the value scatters by 2.9 % and the interval's upper half-width was
// 0.5 %. With the polynomial's variance: 72/100 and 157/200 (upper half-width 2.6 %). Seeds
// 64000..64059 here (29/60 with one point's, 47/60 now); asserted within 68.3 +- 15 points (a
// calibrated cell of 60 is outside that with probability 2 %).
TEST(NoiseCoverage, ThePaperMethodsBoundsHoldBOnFlickerAlone) {
  const Set set{"flicker alone", {0, 0, 3e-4, 0, 0}, 50, 2000.0 / 3600};
  int held = 0, runs = 0;
  for (const Cell& c : run_coverage({set}, 60, 64000, false, nullptr, kOneSigma))
    if (c.term == "B") held = c.covered, runs = c.runs;
  std::printf("paper-method B held %d/%d\n", held, runs);
  ASSERT_EQ(runs, 60);
  EXPECT_NEAR(static_cast<double>(held) / runs, kOneSigma, 0.15);
}

// What the fit assumes of its points holds on simulated records: at the true terms, the mean and
// covariance of ln s_i at the octave points (model_log_scatter: the log-chi-square bias, 2/nu_i
// from the model's EDF, the octave correlations) against 60 records each of the K-dominant and
// the R-dominant set at CI rates (seeds fixed before looking: 31000.., 32000..). With 60 records
// a point's measured sd scatters by about 9 % and the mean chi-square by about 6 %, so the
// limits (sd within 0.7-1.4x, chi-square within 0.75-1.3x the number of points, means within
// 0.6 sd) fail only when an assumption is off. A covariance too small makes the bounds too
// narrow; too large, too wide. At the full rate the R set's last point (T/4) measures 1.18x the
// assumed sd (coverage_noise --covariance, docs/analysis.md).
TEST(NoiseCoverage, TheFitsAssumptionsHoldOnSimulatedRecords) {
  const std::vector<Set> all = sets(true);
  for (const auto& [set, base] : {std::pair{all[2], 31000}, std::pair{all[3], 32000}}) {
    const ScatterCheck c = check_log_scatter(set, 60, static_cast<std::uint64_t>(base));
    ASSERT_GE(c.points(), 10u) << set.name;
    const double P = static_cast<double>(c.points());
    EXPECT_GT(c.chi2, 0.75 * P) << set.name;
    EXPECT_LT(c.chi2, 1.3 * P) << set.name;
    for (std::size_t i = 0; i < c.points(); ++i) {
      const double sd = c.model_sd(i);
      EXPECT_GT(c.sd[i], 0.7 * sd) << set.name << " tau " << c.tau[i];
      EXPECT_LT(c.sd[i], 1.4 * sd) << set.name << " tau " << c.tau[i];
      EXPECT_NEAR(c.mean[i], c.model.bias[i], 0.6 * sd) << set.name << " tau " << c.tau[i];
    }
  }
}

}  // namespace rig::analysis::injected
