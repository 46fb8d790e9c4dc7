// The speed target, part 1: OADEV of 3.6e6 frequency samples (60 min at 1 kHz),
// ~100 log-spaced taus (log:100 -> 90 distinct m), full overlap, with noise identification
// and bounds. Compare with bench/analysis/oadev_numpy.py on the same data (docs/analysis.md).
//
//   build-A/bin/bench_analysis [--benchmark_filter=...]
//   build-A/bin/bench_analysis --data FILE.f64   (the file make_signal.py writes; default: in-process signal)
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <random>
#include <string>

#include "analysis/allan.hpp"
#include "analysis/allan_kernels.hpp"
#include "analysis/noise_terms.hpp"
#include "analysis/psd.hpp"

namespace an = rig::analysis;

namespace {

std::string g_data_file;

const std::vector<double>& record() {
  static const std::vector<double> y = [] {
    std::vector<double> v;
    if (!g_data_file.empty()) {
      std::ifstream f(g_data_file, std::ios::binary | std::ios::ate);
      v.resize(static_cast<std::size_t>(f.tellg()) / 8);
      f.seekg(0);
      f.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(v.size() * 8));
      return v;
    }
    // White noise at the paper's N plus a random walk at its K, and the bias.
    std::mt19937_64 rng(1);
    std::normal_distribution<double> g(0, 1);
    v.resize(3'600'000);
    const double tau0 = 1e-3, N = 2.2306e-7 * 60, K = 5.1167e-6 / 60;
    double walk = 0;
    for (auto& x : v) {
      walk += K * std::sqrt(tau0) * g(rng);
      x = -5.0137e-4 + N / std::sqrt(tau0) * g(rng) + walk;
    }
    return v;
  }();
  return y;
}

void run_dev(benchmark::State& st, an::Deviation type, bool bounds, unsigned threads) {
  const auto& y = record();
  an::DevOptions o;
  o.type = type;
  o.rate_hz = 1000;
  o.taus = an::parse_tau_grid("log:100");
  o.bounds = bounds;
  o.threads = threads;
  std::size_t taus = 0;
  for (auto _ : st) {
    const auto pts = an::deviation(y, o);
    taus = pts.size();
    benchmark::DoNotOptimize(pts.data());
  }
  st.counters["taus"] = static_cast<double>(taus);
  st.counters["samples"] = static_cast<double>(y.size());
}

void BM_OadevBounds2Threads(benchmark::State& st) { run_dev(st, an::Deviation::OADEV, true, 2); }
void BM_OadevBounds1Thread(benchmark::State& st) { run_dev(st, an::Deviation::OADEV, true, 1); }
void BM_OadevNoBounds2Threads(benchmark::State& st) { run_dev(st, an::Deviation::OADEV, false, 2); }
void BM_MdevBounds2Threads(benchmark::State& st) { run_dev(st, an::Deviation::MDEV, true, 2); }
void BM_TotdevBounds2Threads(benchmark::State& st) { run_dev(st, an::Deviation::TOTDEV, true, 2); }

void BM_NoiseTerms(benchmark::State& st) {
  an::DevOptions o;
  o.rate_hz = 1000;
  o.taus = an::parse_tau_grid("log:100");
  const auto pts = an::deviation(record(), o);
  for (auto _ : st) benchmark::DoNotOptimize(an::noise_terms(pts, 3600).B.value);
}

void BM_Welch(benchmark::State& st) {
  for (auto _ : st) benchmark::DoNotOptimize(an::welch(record(), 1000).psd.data());
}

// MDEV's kernel alone, one thread, 4e6 terms whose four windows are m apart in a 136 MB phase
// array: how much of a term's cost is the running sum (m = 1, every window in L1) and how much
// is reading three windows that no cache holds (m >= 1e6: the 50-h record's long taus). The
// counters give terms per second and the bytes per second read from the three lagged windows.
void BM_MdevKernelLag(benchmark::State& st) {
  const std::size_t m = static_cast<std::size_t>(st.range(0)), len = 4'000'000;
  static const std::vector<double> p = [] {
    std::vector<double> v(17'000'000);
    std::mt19937_64 rng(2);
    std::normal_distribution<double> g(0, 1);
    double x = 0;
    for (auto& e : v) e = x += g(rng);
    return v;
  }();
  std::size_t rep = 0;
  for (auto _ : st) {
    // Another base each round, so a round does not find the last one's windows in the caches.
    const std::size_t base = (rep++ * 7'919'000) % (p.size() - 3 * m - len);
    double inner = 0;
    benchmark::DoNotOptimize(rig::analysis::detail::kernels::mdev_run(&p[base], &p[base + m], &p[base + 2 * m],
                                                                       &p[base + 3 * m], len, m, inner));
  }
  const double rounds = static_cast<double>(st.iterations());
  st.counters["terms_per_s"] = benchmark::Counter(static_cast<double>(len) * rounds, benchmark::Counter::kIsRate);
  st.counters["lagged_bytes_per_s"] = benchmark::Counter(3.0 * 8 * static_cast<double>(len) * rounds,
                                                         benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK(BM_MdevKernelLag)->Arg(1)->Arg(4096)->Arg(262144)->Arg(1 << 20)->Arg(4 << 20)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OadevBounds2Threads)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_OadevBounds1Thread)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_OadevNoBounds2Threads)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MdevBounds2Threads)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_TotdevBounds2Threads)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_NoiseTerms)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Welch)->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--data") == 0) {
      g_data_file = argv[i + 1];
      for (int j = i; j + 2 <= argc; ++j) argv[j] = argv[j + 2];
      argc -= 2;
      break;
    }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
