// Speed of the emulated DUT: output samples per second and the real-time factor
// (1 kHz output = 10 loop periods each). Target (issue 4): the paper procedure's
// 110 min (6.6e6 samples) in well under 10 s, i.e. >= 660x real time for the whole rig.
#include <benchmark/benchmark.h>

#include <memory>

#include "plant/dut/emulated_dut.hpp"
#include "plant/dut/period_noise.hpp"

namespace {

void run(benchmark::State& state, const char* overrides) {
  toml::table over = toml::parse(overrides);
  rig::plant::EmulatedDut dut(rig::plant::load_dut_params(&over), 1);
  double x = 0, y = 0, acc = 0;
  for (auto _ : state) {
    dut.next(x, y);
    acc += x + y;
  }
  benchmark::DoNotOptimize(acc);
  const double n = static_cast<double>(state.iterations());
  state.counters["samples/s"] = benchmark::Counter(n, benchmark::Counter::kIsRate);
  // real-time factor: seconds of DUT time per second of wall time
  state.counters["x_realtime"] = benchmark::Counter(n / dut.output_rate_hz(), benchmark::Counter::kIsRate);
  state.counters["ns/loop_step"] =
      benchmark::Counter(n * 10, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_DutDefault(benchmark::State& s) { run(s, ""); }
void BM_DutQuiet(benchmark::State& s) { run(s, "[noise]\nenabled = false\n"); }
void BM_DutNoFilter(benchmark::State& s) { run(s, "[filter]\npreset = \"none\"\n"); }

// The whole paper procedure's DUT time in one go: 110 min = 6.6e6 output samples.
void BM_PaperProcedureDutTime(benchmark::State& state) {
  for (auto _ : state) {
    rig::plant::EmulatedDut dut(rig::plant::load_dut_params(nullptr), 1);
    double x = 0, y = 0, acc = 0;
    for (int i = 0; i < 6'600'000; ++i) {
      dut.next(x, y);
      acc += x;
    }
    benchmark::DoNotOptimize(acc);
  }
}

// The noise worker alone (PeriodNoise::fill on one thread, the default DUT): in the `paper`
// procedure it runs beside the loop model and is half the process's CPU (perf, 2026-12-06).
void BM_PeriodNoise(benchmark::State& state) {
  const rig::plant::DutParams p = rig::plant::load_dut_params(nullptr);
  const std::size_t steps = 10, periods = 100;
  rig::plant::PeriodNoise noise(p, 1, steps);
  auto storage = std::make_unique<double[]>(rig::plant::NoiseBlock::doubles(periods, steps));
  rig::plant::NoiseBlock b(periods, steps, storage.get());
  for (auto _ : state) {
    noise.fill(b);
    benchmark::DoNotOptimize(b.intf[0]);
  }
  state.counters["ns/period"] = benchmark::Counter(static_cast<double>(state.iterations() * periods),
                                                   benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK(BM_PeriodNoise)->MinTime(1.0);
BENCHMARK(BM_DutDefault)->MinTime(1.0);
BENCHMARK(BM_DutQuiet)->MinTime(1.0);
BENCHMARK(BM_DutNoFilter)->MinTime(1.0);
BENCHMARK(BM_PaperProcedureDutTime)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK_MAIN();
