// The engine itself: tau grids and stop ratios, streaming (small ring, far cursors, a real
// file through pread) equal to the in-memory result, frequency/phase equivalence, threads,
// white-noise theory, and input errors.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>

#include "analysis/allan.hpp"

namespace rig::analysis {
namespace {

constexpr Deviation kAll[] = {Deviation::ADEV, Deviation::OADEV, Deviation::MDEV, Deviation::TDEV,
                              Deviation::HDEV, Deviation::OHDEV, Deviation::TOTDEV};

// White FM + random-walk FM + a bias, the shape of an accelerometer record.
std::vector<double> signal(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  std::vector<double> y(n);
  double walk = 0;
  for (auto& v : y) {
    walk += 2e-3 * g(rng);
    v = -5e-4 + 0.05 * g(rng) + walk * 1e-2;
  }
  return y;
}

TEST(TauGrid, ParsesTheFourKindsAndRejectsOthers) {
  EXPECT_EQ(parse_tau_grid("octave").kind, TauGrid::Octave);
  EXPECT_EQ(parse_tau_grid("decade").kind, TauGrid::Decade);
  EXPECT_EQ(parse_tau_grid("all").kind, TauGrid::All);
  const TauGrid g = parse_tau_grid("log:37");
  EXPECT_EQ(g.kind, TauGrid::Log);
  EXPECT_EQ(g.log_n, 37);
  for (const char* bad : {"", "octaves", "log:", "log:x", "log:1", "log:12x", "log:-5", "log:+5", "log:010", "log: 5",
                          "log:100001", "log:99999999999"})
    EXPECT_THROW(parse_tau_grid(bad), std::invalid_argument) << bad;
}

TEST(TauGrid, UsesStable32StopRatios) {
  // PHASE.DAT has 1001 phase points: the reference tables stop at these factors.
  EXPECT_EQ(tau_factors(parse_tau_grid("octave"), Deviation::OADEV, 1001).back(), 128u);
  EXPECT_EQ(tau_factors(parse_tau_grid("octave"), Deviation::TOTDEV, 1001).back(), 256u);
  EXPECT_EQ(tau_factors(parse_tau_grid("all"), Deviation::OADEV, 1001).back(), 250u);
  EXPECT_EQ(tau_factors(parse_tau_grid("all"), Deviation::ADEV, 1001).back(), 200u);
  EXPECT_EQ(tau_factors(parse_tau_grid("all"), Deviation::TOTDEV, 1001).back(), 500u);
  const auto dec = tau_factors(parse_tau_grid("decade"), Deviation::OADEV, 556990);
  const std::vector<std::size_t> want = {1, 2, 4, 10, 20, 40, 100, 200, 400, 1000, 2000, 4000,
                                         10000, 20000, 40000, 100000};
  EXPECT_EQ(dec, want);  // Cs5071A/oadev_decade.txt
  const auto lg = tau_factors(parse_tau_grid("log:100"), Deviation::OADEV, 3600001);
  EXPECT_EQ(lg.front(), 1u);
  EXPECT_LE(lg.back(), 900000u);
  EXPECT_GT(lg.back(), 750000u);
  EXPECT_TRUE(std::is_sorted(lg.begin(), lg.end()));
  EXPECT_GT(lg.size(), 90u);
  EXPECT_LT(lg.size(), 120u);
  // Doubling-closed above 64 (the engine shares windows along m, 2m, 4m ...).
  for (std::size_t m : lg) {
    if (m >= 64 && 2 * m <= 900000) {
      EXPECT_TRUE(std::binary_search(lg.begin(), lg.end(), 2 * m)) << m;
    }
  }
}

// docs/analysis.md's rule for log:N, pinned by the review's counts on 1e5 values (OADEV's
// largest factor 25000): q = max(1, ceil((N-1)/log2(top))) points per octave, never fewer than
// one (log:2 is the octave grid), at most 64 from m = 64 on (its seeds are whole numbers in
// [64, 128)).
TEST(TauGrid, LogNFollowsTheDocumentedRule) {
  const auto count = [](const char* grid) { return tau_factors(parse_tau_grid(grid), Deviation::OADEV, 100001).size(); };
  EXPECT_EQ(tau_factors(parse_tau_grid("log:2"), Deviation::OADEV, 100001),
            tau_factors(parse_tau_grid("octave"), Deviation::OADEV, 100001));
  EXPECT_EQ(count("log:2"), 15u);
  EXPECT_EQ(count("log:10"), 15u);
  EXPECT_EQ(count("log:20"), 29u);
  EXPECT_EQ(count("log:100"), 89u);
  EXPECT_EQ(count("log:1000"), 585u);
  // The most any N gives: every m below 64 and all 64 seeds 64..127 with their doublings up to
  // 25000 (63 + 8 x 64 + 34).
  EXPECT_EQ(count("log:100000"), 609u);
}

TEST(TermCount, FollowsTheReferenceReadme) {
  EXPECT_EQ(term_count(Deviation::ADEV, 1001, 2), 499u);
  EXPECT_EQ(term_count(Deviation::OADEV, 1001, 2), 997u);
  EXPECT_EQ(term_count(Deviation::MDEV, 1001, 2), 996u);
  EXPECT_EQ(term_count(Deviation::HDEV, 1001, 2), 498u);
  EXPECT_EQ(term_count(Deviation::OHDEV, 1001, 2), 995u);
  EXPECT_EQ(term_count(Deviation::TOTDEV, 1001, 2), 999u);
}

void expect_same(const std::vector<DevPoint>& a, const std::vector<DevPoint>& b, double tol, const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].m, b[i].m) << what;
    EXPECT_EQ(a[i].n_terms, b[i].n_terms) << what << " m=" << a[i].m;
    EXPECT_NEAR(a[i].dev, b[i].dev, tol * a[i].dev) << what << " m=" << a[i].m;
    EXPECT_EQ(a[i].alpha, b[i].alpha) << what << " m=" << a[i].m;
    // The EDF follows from alpha, m and N alone (computed in the parallel noise-ID loop for the
    // ACF taus, in order for the B1 taus and the EDF guard): equal, not near.
    EXPECT_EQ(a[i].edf, b[i].edf) << what << " m=" << a[i].m;
    EXPECT_EQ(a[i].edf_alpha, b[i].edf_alpha) << what << " m=" << a[i].m;
    EXPECT_NEAR(a[i].lo, b[i].lo, tol * a[i].dev + 1e-300) << what << " m=" << a[i].m;
    EXPECT_NEAR(a[i].hi, b[i].hi, tol * a[i].dev + 1e-300) << what << " m=" << a[i].m;
  }
}

TEST(Stream, SmallRingAndFarCursorsEqualTheInMemoryResult) {
  const auto y = signal(150000, 7);
  for (Deviation d : kAll) {
    DevOptions o;
    o.type = d;
    o.rate_hz = 1000;
    o.taus = parse_tau_grid("log:40");
    const auto mem = deviation(y, o);
    // 1 MiB budget: a ring of 64k points, so the larger factors go through the cursors.
    StreamOptions so;
    so.memory_budget_bytes = 1u << 20;
    so.chunk = 4096;
    SpanSource src(y);
    const auto str = deviation_stream(src, o, so);
    expect_same(mem, str, 1e-12, to_string(d));
  }
}

TEST(Stream, TotdevWithOadevSharesItsInteriorAndEqualsTotdevAlone) {
  // With OADEV in the same pass, TOTDEV's interior terms are OADEV's sums at the same m (SP 1065
  // eq. 25 vs eq. 11): run once, only the reflected edges added. The result must equal TOTDEV
  // computed on its own, in memory and streamed through a small ring (far and cursor taus).
  const auto y = signal(150000, 11);
  DevOptions oa, tot;
  oa.type = Deviation::OADEV;
  tot.type = Deviation::TOTDEV;
  for (DevOptions* o : {&oa, &tot}) o->rate_hz = 1000, o->taus = parse_tau_grid("log:40");
  const auto alone = deviation(y, tot);
  const DevOptions both[] = {oa, tot};
  SpanSource src(y);
  StreamOptions in_memory;
  in_memory.memory_budget_bytes = std::size_t{1} << 40;
  expect_same(alone, deviations_stream(src, both, in_memory)[1], 1e-12, "in memory");
  StreamOptions small;
  small.memory_budget_bytes = 1u << 20;
  small.chunk = 4096;
  const auto streamed = deviations_stream(src, both, small);
  expect_same(alone, streamed[1], 1e-12, "streamed");
  expect_same(deviation(y, oa), streamed[0], 1e-12, "its OADEV");
}

// TOTDEV written out as SP 1065 eq. 25 says: the phase extended by odd reflection at both ends,
// centred second differences at i = 1 .. N-2, no engine. The engine's edge blocks (paired with
// their mirror blocks when m spans several) must give the same, in memory and streamed.
TEST(Stream, TotdevEqualsTheReflectedSeriesWrittenOut) {
  const auto y = signal(30001, 13);
  const std::size_t n = y.size() + 1;
  std::vector<double> x(n, 0.0);  // phase in units of tau0 (the scale cancels in the ratio below)
  for (std::size_t i = 1; i < n; ++i) x[i] = x[i - 1] + y[i - 1];
  auto xe = [&](long long j) {  // x*(j) of eq. 25, 0-based
    const long long last = static_cast<long long>(n) - 1;
    if (j < 0) return 2 * x[0] - x[static_cast<std::size_t>(-j)];
    if (j > last) return 2 * x[n - 1] - x[static_cast<std::size_t>(2 * last - j)];
    return x[static_cast<std::size_t>(j)];
  };
  DevOptions o;
  o.type = Deviation::TOTDEV;
  o.rate_hz = 1;
  o.bounds = false;
  o.factors = {1, 2, 7, 1000, 2500, 9000, 15000};  // up to (N-1)/2, several edge blocks each
  SpanSource src(y);
  StreamOptions mem, small;
  mem.memory_budget_bytes = std::size_t{1} << 40;
  mem.chunk = 1024;
  small.memory_budget_bytes = 96u << 10;
  small.chunk = 1024;
  for (const StreamOptions* so : {&mem, &small}) {
    const auto got = deviation_stream(src, o, *so);
    ASSERT_EQ(got.size(), o.factors.size());
    for (std::size_t k = 0; k < got.size(); ++k) {
      const long long m = static_cast<long long>(o.factors[k]);
      double sum = 0;
      for (long long i = 1; i + 1 < static_cast<long long>(n); ++i) {
        const double d = xe(i - m) - 2 * xe(i) + xe(i + m);
        sum += d * d;
      }
      const double want = std::sqrt(sum / (2.0 * static_cast<double>(m * m) * static_cast<double>(n - 2)));
      EXPECT_NEAR(got[k].dev, want, 1e-11 * want) << "m=" << m << (so == &mem ? " in memory" : " streamed");
    }
  }
}

// `o` computed on one thread and on two must agree bit for bit.
void expect_one_thread_equals_two(const std::vector<double>& y, DevOptions o) {
  o.threads = 1;
  const auto one = deviation(y, o);
  o.threads = 2;
  const auto two = deviation(y, o);
  expect_same(one, two, 0.0, to_string(o.type));
}

TEST(Stream, OneThreadEqualsTwo) {
  // In memory every deviation's heads are cut into fixed segments (MDEV/TDEV restart their
  // window sum at each): the sums must not depend on which thread ran which segment.
  const auto y = signal(100000, 3);
  for (Deviation d : kAll) {
    DevOptions o;
    o.type = d;
    o.taus = parse_tau_grid("log:30");
    expect_one_thread_equals_two(y, o);
  }
}

TEST(Stream, InMemoryPhaseBuiltOnTwoThreadsEqualsTheSequentialBuildBitForBit) {
  // From 2^20 points the in-memory phase is built in two parts on two threads, the second
  // starting from block sums of the first: every deviation must come out bit for bit as from
  // the one-thread (sequential) build, for frequency and phase data.
  auto y = signal(1200000, 11);
  for (double& v : y) v += 3.0;  // a large mean: the checkpoints' running sum is far from 0
  for (DataKind kind : {DataKind::Frequency, DataKind::Phase})
    for (Deviation d : {Deviation::OADEV, Deviation::MDEV, Deviation::TOTDEV}) {
      DevOptions o;
      o.type = d;
      o.data = kind;
      o.taus = parse_tau_grid("log:20");
      expect_one_thread_equals_two(y, o);
    }
}

TEST(Stream, StreamingOneThreadEqualsTwoAndRepeats) {
  // The streaming pass (a barrier per chunk, the next chunk built as a work item, cursors for
  // the long taus) must not depend on which thread ran what.
  const auto y = signal(120000, 5);
  for (Deviation d : {Deviation::OADEV, Deviation::MDEV, Deviation::OHDEV, Deviation::TOTDEV}) {
    DevOptions o;
    o.type = d;
    o.taus = parse_tau_grid("log:30");
    StreamOptions so;
    so.memory_budget_bytes = 1u << 20;
    so.chunk = 4096;
    SpanSource src(y);
    o.threads = 1;
    const auto one = deviation_stream(src, o, so);
    o.threads = 2;
    const auto two = deviation_stream(src, o, so);
    const auto again = deviation_stream(src, o, so);
    expect_same(one, two, 0.0, to_string(d));
    expect_same(two, again, 0.0, to_string(d));
  }
}

// A source whose reads fail from a given value on (a file that goes bad mid-record).
class FailingSource final : public ChunkSource {
 public:
  FailingSource(std::span<const double> v, std::uint64_t bad_from) : v_(v), bad_from_(bad_from) {}
  std::uint64_t size() const override { return v_.size(); }
  std::size_t read_at(std::uint64_t pos, std::span<double> out) const override {
    const std::size_t n = std::min<std::size_t>(out.size(), v_.size() - pos);
    if (pos + n > bad_from_) throw std::runtime_error("read error at value " + std::to_string(bad_from_));
    std::copy_n(v_.begin() + static_cast<std::ptrdiff_t>(pos), n, out.begin());
    return n;
  }

 private:
  std::span<const double> v_;
  std::uint64_t bad_from_;
};

TEST(Stream, AReadErrorOnEitherThreadReachesTheCaller) {
  // The next chunk is read as a work item, so the error may surface on the worker thread: it
  // must come back to the caller as the exception, not end the process.
  const auto y = signal(120000, 8);
  for (unsigned threads : {1u, 2u})
    for (std::uint64_t bad_from : {std::uint64_t{100}, std::uint64_t{70000}, std::uint64_t{119990}}) {
      DevOptions o;
      o.taus = parse_tau_grid("log:30");
      o.threads = threads;
      StreamOptions so;
      so.memory_budget_bytes = 1u << 20;
      so.chunk = 4096;
      FailingSource src(y, bad_from);
      EXPECT_THROW(deviation_stream(src, o, so), std::runtime_error) << threads << " threads, bad from " << bad_from;
    }
}

// A float64 file read with pread, as `rig analyze --input f64` does.
class PreadSource final : public ChunkSource {
 public:
  explicit PreadSource(const std::string& p) : fd_(::open(p.c_str(), O_RDONLY)) {
    n_ = static_cast<std::uint64_t>(::lseek(fd_, 0, SEEK_END)) / 8;
  }
  ~PreadSource() override { ::close(fd_); }
  std::uint64_t size() const override { return n_; }
  std::size_t read_at(std::uint64_t pos, std::span<double> out) const override {
    const std::size_t want = static_cast<std::size_t>(std::min<std::uint64_t>(out.size(), n_ - pos));
    const ssize_t r = ::pread(fd_, out.data(), want * 8, static_cast<off_t>(pos * 8));
    return r > 0 ? static_cast<std::size_t>(r) / 8 : 0;
  }

 private:
  int fd_;
  std::uint64_t n_ = 0;
};

TEST(Stream, RealFileThroughPreadEqualsMemory) {
  const auto y = signal(120000, 11);
  const auto path = std::filesystem::temp_directory_path() / ("rig_allan_" + std::to_string(::getpid()) + ".f64");
  {
    std::ofstream f(path, std::ios::binary);
    f.write(reinterpret_cast<const char*>(y.data()), static_cast<std::streamsize>(y.size() * 8));
  }
  DevOptions o;
  o.rate_hz = 1000;
  o.taus = parse_tau_grid("octave");
  PreadSource src(path.string());
  StreamOptions so;
  so.memory_budget_bytes = 1u << 20;
  const auto from_file = deviation_stream(src, o, so);
  std::filesystem::remove(path);
  expect_same(deviation(y, o), from_file, 1e-12, "file");
}

TEST(Allan, FrequencyAndItsPhaseGiveTheSameDeviations) {
  const auto y = signal(20000, 5);
  const double rate = 50;
  std::vector<double> x(y.size() + 1, 0.0);
  for (std::size_t i = 0; i < y.size(); ++i) x[i + 1] = x[i] + y[i] / rate;
  for (Deviation d : kAll) {
    DevOptions fo;
    fo.type = d;
    fo.rate_hz = rate;
    fo.bounds = false;
    DevOptions po = fo;
    po.data = DataKind::Phase;
    const auto a = deviation(y, fo), b = deviation(x, po);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i].dev, b[i].dev, 1e-8 * a[i].dev) << to_string(d);
  }
}

TEST(Allan, WhiteFrequencyNoiseFollowsSigmaOverRootM) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> g(0, 1);
  std::vector<double> y(400000);
  for (auto& v : y) v = 3.0 * g(rng);
  DevOptions o;
  o.confidence = 0.99;
  o.taus = parse_tau_grid("octave");
  for (const auto& p : deviation(y, o)) {
    const double truth = 3.0 / std::sqrt(static_cast<double>(p.m));
    EXPECT_LT(p.lo, truth) << "m=" << p.m;
    EXPECT_GT(p.hi, truth) << "m=" << p.m;
    if (p.m <= 4096) {
      EXPECT_EQ(p.alpha, 0) << "m=" << p.m;  // white FM identified
    }
  }
}

TEST(Allan, ExplicitFactorsAndBoundsOff) {
  const auto y = signal(5000, 2);
  DevOptions o;
  o.factors = {1, 3, 7};
  o.bounds = false;
  const auto p = deviation(y, o);
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p[1].m, 3u);
  EXPECT_EQ(p[1].lo, 0.0);
  EXPECT_EQ(p[1].edf, 0.0);
  o.factors = {0};
  EXPECT_THROW(deviation(y, o), std::invalid_argument);
  o.factors = {4000};
  EXPECT_THROW(deviation(y, o), std::invalid_argument);
}

// MDEV and TDEV at m = N/3 of N phase points: one term, |x(2m) - 2x(m) + x(0)| over its window
// sum (NIST SP 1065 eq. 14 with one j). It came out NaN (0 over 0 terms: no base after the first
// term primed it, a review), in memory and streamed, with bounds and without.
TEST(Allan, MdevAndTdevOfOneTermAreItsWindowSum) {
  for (std::size_t n : {3u, 6u, 30u, 300u, 30000u}) {
    std::vector<double> x(n);
    for (std::size_t i = 0; i < n; ++i) x[i] = std::sin(0.37 * static_cast<double>(i * i % 101)) * 1e-3;
    const std::size_t m = n / 3;
    double w = 0;
    for (std::size_t i = 0; i < m; ++i) w += x[i + 2 * m] - 2 * x[i + m] + x[i];
    const double mm = static_cast<double>(m), mdev = std::sqrt(w * w / (2 * mm * mm * mm * mm));
    for (Deviation d : {Deviation::MDEV, Deviation::TDEV})
      for (bool bounds : {true, false}) {
        DevOptions o;
        o.type = d;
        o.data = DataKind::Phase;
        o.factors = {m};
        o.bounds = bounds;
        const auto p = deviation(x, o);
        ASSERT_EQ(p.size(), 1u);
        EXPECT_EQ(p[0].n_terms, 1u);
        const double want = d == Deviation::MDEV ? mdev : mdev * mm / std::sqrt(3.0);
        EXPECT_NEAR(p[0].dev, want, 1e-12 * want) << to_string(d) << " n " << n;
        StreamOptions so;
        so.memory_budget_bytes = 1u << 20;
        so.chunk = 4096;
        SpanSource src(x);
        const auto str = deviation_stream(src, o, so);
        EXPECT_NEAR(str[0].dev, p[0].dev, 1e-12 * want) << to_string(d) << " n " << n << " streamed";
      }
  }
}

// A rate ramp y = R t: MDEV = R tau / sqrt(2), TDEV = R tau^2 / sqrt(6), OADEV = R tau / sqrt(2)
// (NIST SP 1065 Table 5 for a frequency drift). Its phase is a quadratic, large beside the window
// sums at short tau: MDEV slid its window sum by third differences of it and read 5e-6 high at
// m = 1, 8e-9 at m = 8, where OADEV was exact (a metrologist's review). In memory and streamed.
TEST(Allan, MdevOfARateRampHoldsItsDigitsAtShortTau) {
  const double rate = 100, R = 1e-6;
  std::vector<double> y(200000);
  for (std::size_t i = 0; i < y.size(); ++i) y[i] = R * static_cast<double>(i) / rate;
  for (Deviation d : {Deviation::MDEV, Deviation::TDEV, Deviation::OADEV}) {
    DevOptions o;
    o.type = d;
    o.rate_hz = rate;
    o.bounds = false;
    o.factors = {1, 2, 3, 5, 8, 9, 16, 64, 1024};
    StreamOptions so;
    so.memory_budget_bytes = 1u << 20;
    so.chunk = 4096;
    SpanSource src(y);
    const auto mem = deviation(y, o), str = deviation_stream(src, o, so);
    ASSERT_EQ(mem.size(), o.factors.size());
    for (std::size_t i = 0; i < mem.size(); ++i) {
      const double tau = static_cast<double>(mem[i].m) / rate;
      const double want = d == Deviation::TDEV ? R * tau * tau / std::sqrt(6.0) : R * tau / std::sqrt(2.0);
      EXPECT_NEAR(mem[i].dev, want, 1e-9 * want) << to_string(d) << " m " << mem[i].m;
      EXPECT_NEAR(str[i].dev, want, 1e-9 * want) << to_string(d) << " m " << mem[i].m << " streamed";
    }
  }
}

TEST(Allan, RejectsBadInputNamingTheProblem) {
  DevOptions o;
  EXPECT_THROW(deviation(std::vector<double>{1.0}, o), std::invalid_argument);
  std::vector<double> y(100, 1.0);
  y[42] = std::nan("");
  try {
    deviation(y, o);
    FAIL() << "NaN accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("42"), std::string::npos) << e.what();
  }
  // Finite but beyond any measurement: the sums would overflow and every point read inf.
  y[42] = 1e300;
  try {
    deviation(y, o);
    FAIL() << "1e300 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("value 42 (1.0000000000000001e+300) is beyond"), std::string::npos)
        << e.what();
  }
  y[42] = 1;
  o.rate_hz = 0;
  EXPECT_THROW(deviation(y, o), std::invalid_argument);
  o.rate_hz = 1;
  o.confidence = 1.5;
  EXPECT_THROW(deviation(y, o), std::invalid_argument);
  EXPECT_THROW(parse_deviation("avar"), std::invalid_argument);
  EXPECT_EQ(parse_deviation("ohdev"), Deviation::OHDEV);
}

TEST(Allan, FirstUnusableFindsNanInfAndHugeValuesAtAnyLane) {
  std::vector<double> v(37, -2.5);
  EXPECT_FALSE(first_unusable(v));
  v[36] = 1e-310;  // subnormal: usable
  v[35] = std::nextafter(-kMaxMagnitude, 0.0);  // the largest usable magnitude
  EXPECT_FALSE(first_unusable(v));
  for (std::size_t at : {0u, 3u, 17u, 36u})
    for (double bad : {std::nan(""), -std::numeric_limits<double>::infinity(), -kMaxMagnitude, 2e100, 1e308}) {
      std::vector<double> w = v;
      w[at] = bad;
      w[at == 36 ? 0 : 36] = bad;  // a later one too: the first is reported
      ASSERT_TRUE(first_unusable(w));
      EXPECT_EQ(*first_unusable(w), std::min<std::size_t>(at, at == 36 ? 0 : 36)) << bad;
    }
  // Every lane of the vectorised pass's four 8-wide accumulators, and its scalar tail.
  std::vector<double> u(70, 1.0);
  for (std::size_t at = 0; at < u.size(); ++at)
    for (double bad : {std::nan(""), kMaxMagnitude}) {
      std::vector<double> w = u;
      w[at] = bad;
      ASSERT_TRUE(first_unusable(w)) << at;
      EXPECT_EQ(*first_unusable(w), at);
    }
}

}  // namespace
}  // namespace rig::analysis
