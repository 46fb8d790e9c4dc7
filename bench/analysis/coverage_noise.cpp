// Coverage of the noise-term bounds over injected-noise records (tests/analysis/injected_noise.hpp):
//   coverage_noise [SEEDS=20] [BASE_SEED=12000] [--ci]
// prints the Markdown coverage table of docs/analysis.md. Full size: 1 h at 1 kHz, 6 h at
// 100 Hz, 60 h at 10 Hz (about 5 min on the 2-core rig PC for 20 seeds); --ci: the test's
// rates (10x lower).
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "tests/analysis/noise_coverage.hpp"

int main(int argc, char** argv) {
  int seeds = 20;
  unsigned long long base = 12000;
  bool ci = false;
  int pos = 0;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--ci")) ci = true;
    else if (pos++ == 0) seeds = std::atoi(argv[i]);
    else base = std::strtoull(argv[i], nullptr, 10);
  }
  using namespace rig::analysis::injected;
  const auto cells = run_coverage(sets(ci), seeds, base, true);
  std::printf("%d seeds per set from %llu%s\n\n%s", seeds, base, ci ? " (CI rates)" : "", coverage_table(cells).c_str());
  return 0;
}
