// The EDF guard (analysis/allan.hpp DevOptions::edf_guard, docs/analysis.md): where B1 reads a
// noise type from a few averages that contradicts the ACF-identified taus below, the bounds
// may not claim more than twice the EDF of the ACF's type. Issue 12: flicker PM read at the last
// three taus of a random-walk record gave an EDF ~25x too large.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdint>
#include <vector>

#include "analysis/allan.hpp"
#include "analysis/edf.hpp"
#include "analysis/theo.hpp"

namespace rig::analysis {
namespace {

// splitmix64 and Box-Muller: the same record on every platform and standard library.
struct Rng {
  std::uint64_t s;
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1p-53; }
  double gauss() {
    const double a = uniform(), b = uniform();
    return std::sqrt(-2 * std::log(a + 0x1p-60)) * std::cos(6.283185307179586 * b);
  }
};

// Pure random-walk FM (alpha -2): 4096 frequency values, the running sum of white noise. With
// seed 26 the B1 rule reads white FM at AF 256 and flicker PM at AF 512 and 1024, the last
// three octave taus (fewer than 30 averages), while the ACF says RW FM at every tau below.
std::vector<double> random_walk_record() {
  Rng r{26};
  std::vector<double> y(4096);
  double w = 0;
  for (double& v : y) v = (w += r.gauss());
  return y;
}

// White FM: n values of unit variance from the seed's stream.
std::vector<double> white_fm(std::size_t n, std::uint64_t seed) {
  Rng r{seed};
  std::vector<double> y(n);
  for (double& v : y) v = r.gauss();
  return y;
}

std::vector<DevPoint> oadev(const std::vector<double>& y, bool guard) {
  DevOptions o;
  o.type = Deviation::OADEV;
  o.taus = parse_tau_grid("octave");
  o.edf_guard = guard;
  return deviation(y, o);
}

TEST(EdfGuard, RandomWalkRecordWhoseB1FlipsToFlickerPmKeepsTheNeighboursEdf) {
  const auto y = random_walk_record();
  const std::size_t n = y.size() + 1;
  const auto raw = oadev(y, false);
  const auto guarded = oadev(y, true);
  ASSERT_EQ(raw.size(), guarded.size());
  // The record is what the test needs: RW FM identified (ACF) up to AF 128, PM read by B1 above.
  int flipped = 0;
  for (std::size_t i = 0; i < raw.size(); ++i) {
    const DevPoint& r = raw[i];
    const DevPoint& g = guarded[i];
    EXPECT_EQ(r.alpha, g.alpha) << "AF " << r.m << ": the identification itself is Stable32's";
    EXPECT_DOUBLE_EQ(r.dev, g.dev);
    if (r.m <= 128) {
      EXPECT_EQ(r.alpha, -2) << "AF " << r.m;
      EXPECT_EQ(g.edf, r.edf) << "AF " << r.m << ": the guard acts only where B1 identifies";
      continue;
    }
    const double rw_edf = edf_greenhall(-2, 2, r.m, n, true, false);
    if (r.alpha >= 1) {
      ++flipped;
      EXPECT_GT(r.edf, 5 * rw_edf) << "AF " << r.m << ": unguarded, PM claims several times RW FM's EDF";
      EXPECT_DOUBLE_EQ(g.edf, rw_edf) << "AF " << r.m;
      EXPECT_EQ(g.edf_alpha, -2) << "AF " << r.m;
      EXPECT_GT(g.hi - g.lo, 2 * (r.hi - r.lo)) << "AF " << r.m << ": honest (wider) bounds";
    } else {
      EXPECT_LE(g.edf, 2 * rw_edf) << "AF " << r.m;
    }
  }
  EXPECT_EQ(flipped, 2) << "the constructed record no longer flips: the test would prove nothing";
}

// Why the threshold is 2: a genuine change between FM types costs less than that (white vs
// random-walk FM at most 1.8x where B1 identifies), a PM reading on an FM curve more than 2x.
TEST(EdfGuard, ThresholdSeparatesFmChangesFromPmReadings) {
  for (std::size_t n : {1001u, 4097u, 100001u, 3600001u})
    for (std::size_t m = (n - 1) / 31 + 1; m <= (n - 1) / 4; m = m * 5 / 4 + 1) {
      const double wf = edf_greenhall(0, 2, m, n, true, false), rw = edf_greenhall(-2, 2, m, n, true, false);
      const double fp = edf_greenhall(1, 2, m, n, true, false);
      EXPECT_LE(wf / rw, 1.8) << "N " << n << " m " << m;
      EXPECT_GT(fp / wf, 2.0) << "N " << n << " m " << m;
    }
}

// The long-tau statistics take OADEV's guarded type: Theo1 beyond AF 512 on the same record is
// bounded as random-walk FM, not as the flicker PM that B1 read.
TEST(EdfGuard, LongTauStatisticsTakeTheGuardedType) {
  const auto y = random_walk_record();
  LongTauOptions o;
  o.type = LongTau::Theo1;
  o.taus = parse_tau_grid("octave");
  o.noise_ref = oadev(y, true);
  ASSERT_EQ(o.noise_ref.back().alpha, 1);  // what B1 read at the last OADEV tau
  const auto pts = long_tau(y, o);
  ASSERT_FALSE(pts.empty());
  for (const LongTauPoint& p : pts)
    if (p.tau_s >= 512) {
      EXPECT_EQ(p.alpha, -2) << "m " << p.m;
      // The table's EDF, where it gives an interval (it is negative at m = 4096 here: none then,
      // and said: LongTauBounds.NoIntervalWhereTheTableEdfGivesNone).
      if (p.bounds_note.empty())
        EXPECT_DOUBLE_EQ(p.edf, edf_theo1(-2, y.size() + 1, p.m)) << "m " << p.m;
      else
        EXPECT_TRUE(std::isnan(p.edf) && !(edf_theo1(-2, y.size() + 1, p.m) > 1)) << "m " << p.m << " " << p.bounds_note;
    }
}

TEST(EdfGuard, AFixedNoiseTypeIsNeverOverridden) {
  const auto y = random_walk_record();
  DevOptions o;
  o.taus = parse_tau_grid("octave");
  o.fixed_alpha = 1;
  for (const DevPoint& p : deviation(y, o)) {
    EXPECT_EQ(p.alpha, 1);
    EXPECT_EQ(p.edf_alpha, 1);
  }
}

// The same guard where the lag-1 ACF reads few values (30 to 99 averages: r1's standard error
// 0.1-0.18): on white-FM records it sometimes reads flicker PM, whose EDF is about 9x white FM's
// there (a review: OADEV's EDF 866 against 96 at AF 1520 of 1e5 values). Guarded, no such point,
// nor a B1 tau beyond it (guarded against the type read from 100 or more: a code review), claims
// more than twice white FM's EDF; the identification printed stays Stable32's.
TEST(EdfGuard, AnAcfReadingFromFewAveragesIsGuardedToo) {
  int misread = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const std::vector<double> y = white_fm(16384, 1000 + seed);
    const std::size_t n = y.size() + 1;
    const auto raw = oadev(y, false), guarded = oadev(y, true);
    for (std::size_t i = 0; i < raw.size(); ++i) {
      const std::size_t averages = y.size() / raw[i].m;
      EXPECT_EQ(raw[i].alpha, guarded[i].alpha);
      const double wfm = edf_greenhall(0, 2, raw[i].m, n, true, false);
      if (averages >= 100) {
        EXPECT_EQ(guarded[i].edf, raw[i].edf) << "seed " << seed << " AF " << raw[i].m << ": read from 100 or more";
        continue;
      }
      if (raw[i].alpha >= 1 && averages >= 30) {  // below 30, B1's taus are held to the same line
        ++misread;
        EXPECT_GT(raw[i].edf, 2 * wfm) << "seed " << seed << " AF " << raw[i].m;
      }
      EXPECT_LE(guarded[i].edf, 2 * wfm) << "seed " << seed << " AF " << raw[i].m;
    }
  }
  EXPECT_GT(misread, 0) << "no ACF misreading in these records: the test shows nothing";
}

// A tau asked for alone is guarded as among its neighbours (an analysis review: white FM, 1000
// values, m:251 alone read flicker PM with EDF 23 where m:250,251 gave 4, its bounds holding the
// truth on 66 % against 79 %): with no requested tau read from 100 or more averages, the guard
// reads a reference tau of its own. Seeds 1..40 fixed before looking; where the lone B1 reading
// misreads, the guarded EDF is the one m:1,251 gives; the deviation and its alpha never change.
TEST(EdfGuard, ATauAskedForAloneIsGuardedAsAmongItsNeighbours) {
  int misread = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const std::vector<double> y = white_fm(1000, 5000 + seed);
    const std::size_t n = y.size() + 1;
    const auto at = [&](std::vector<std::size_t> factors, bool guard) {
      DevOptions o;
      o.type = Deviation::OADEV;
      o.factors = std::move(factors);
      o.edf_guard = guard;
      return deviation(y, o).back();
    };
    const DevPoint alone = at({251}, true), raw = at({251}, false), with_one = at({1, 251}, true);
    EXPECT_EQ(alone.dev, raw.dev);
    EXPECT_EQ(alone.alpha, raw.alpha);
    const double wfm = edf_greenhall(0, 2, 251, n, true, false);
    if (raw.edf > 2 * wfm) ++misread;
    EXPECT_LE(alone.edf, 2 * wfm) << "seed " << seed;
    EXPECT_EQ(alone.edf, with_one.edf) << "seed " << seed;
  }
  EXPECT_GT(misread, 0) << "no lone misreading in these records: the test shows nothing";
}

// TOTDEV's bounds at m = 1 and 2, where TOTDEV is OADEV or nearly so: with Table 7's EDF alone
// (about twice OADEV's there) the 68.3 % bounds held the truth on 50 % and 60 % of white-FM
// records (a metrologist's review). With the EDF capped at OADEV's times the share of terms
// (edf.hpp), over 200 white-FM records of 1000 values, seeds 1..200 fixed before looking, the
// pooled coverage is within 2.7 binomial sigmas (2.3 %) of 68.3 %.
TEST(TotdevEdf, BoundsAtTheShortestTausHoldTheTruthAtTheirStatedRate) {
  int held = 0, n = 0;
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    Rng r{seed};
    std::vector<double> y(1000);
    for (double& v : y) v = r.gauss();  // white FM, sd 1: sigma_y(m) = 1 / sqrt(m)
    DevOptions o;
    o.type = Deviation::TOTDEV;
    o.data = DataKind::Frequency;
    o.rate_hz = 1;
    o.factors = {1, 2};
    o.fixed_alpha = 0;
    for (const DevPoint& p : deviation(y, o)) {
      const double truth = 1 / std::sqrt(static_cast<double>(p.m));
      held += p.lo <= truth && truth <= p.hi;
      ++n;
    }
  }
  const double rate = static_cast<double>(held) / n;
  EXPECT_NEAR(rate, kOneSigma, 0.062) << held << " of " << n;
  std::printf("TOTDEV m = 1, 2: %d of %d bounds held the truth\n", held, n);
}

// The cap holds for the PM alphas too, where SP 1065 gives TOTDEV no EDF and Table 5's simple
// AVAR forms stand in: the flicker-PM form read up to 1.6x OADEV's EDF times the share of terms
// (3178 against 1952 at N = 10000 phase points, m = 16: a review), bounds narrower than OADEV's.
TEST(TotdevEdf, PmNoiseNeverClaimsMoreThanOadevsShareOfTerms) {
  const std::size_t n = 10000;
  bool bound_somewhere = false;
  for (const int alpha : {1, 2})
    for (const std::size_t m : {1, 4, 16, 32, 512, 2500}) {
      const double share = static_cast<double>(n - 2) / static_cast<double>(n - 2 * m);
      const double cap = edf_greenhall(alpha, 2, m, n, true, false) * share;
      EXPECT_LE(edf_totdev(n, m, alpha), cap * (1 + 1e-12)) << "alpha " << alpha << " m " << m;
      bound_somewhere |= edf_simple(n, m, alpha) > cap;
    }
  EXPECT_NEAR(edf_simple(n, 16, 1), 3178, 1) << "the review's figure";
  EXPECT_NEAR(edf_totdev(n, 16, 1), 1952, 1) << "the review's cap: the one that binds";
  EXPECT_TRUE(bound_somewhere);
}

}  // namespace
}  // namespace rig::analysis
