// Coverage of the noise-term bounds over injected-noise records (tests/analysis/injected_noise.hpp):
//   coverage_noise [SEEDS=20] [BASE_SEED=12000] [--ci] [--set NAME] [--covariance]
// prints the Markdown coverage table of docs/analysis.md. Full size: 1 h at 1 kHz, 6 h at
// 100 Hz, 60 h at 10 Hz (about 5 min on the 2-core rig PC for 20 seeds); --ci: the test's
// rates (10x lower). --covariance (with --set): instead of the coverage, what the noise fit
// assumes of its points (the mean and covariance of ln s_i at the true terms, model_log_scatter)
// against what SEEDS records of the set show.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "tests/analysis/noise_coverage.hpp"

namespace {

using namespace rig::analysis;
using namespace rig::analysis::injected;

// The noise fit's assumptions at its points (mean and covariance of ln s_i, model_log_scatter at
// the true terms) against `seeds` records of the set: mean, sd and correlation with the previous
// point of ln(s_i / mu_i), and the mean GLS chi-square of the records at the truth (the number of
// points if the assumed covariance is right).
std::string covariance_table(const Set& s, int seeds, unsigned long long base) {
  const auto n = static_cast<std::size_t>(s.hours * 3600 * s.rate_hz);
  std::array<double, 5> theta{};
  for (std::size_t k = 0; k < 5; ++k) theta[k] = s.truth.at(static_cast<int>(k)) * s.truth.at(static_cast<int>(k));
  std::vector<double> tau;
  std::vector<std::size_t> m;
  std::vector<std::vector<double>> lr;  // per record, ln(s_i / mu_i)
  for (int r = 0; r < seeds; ++r) {
    const std::vector<double> y = generate(s.truth, s.rate_hz, n, base + static_cast<unsigned long long>(r));
    DevOptions opt;
    opt.rate_hz = s.rate_hz;
    opt.taus = parse_tau_grid("log:100");
    opt.bounds = false;
    const std::vector<DevPoint> dev = deviation(y, opt);
    tau.clear(), m.clear();
    std::vector<double> l;
    for (const std::size_t i : octave_points(dev)) {
      tau.push_back(dev[i].tau_s);
      m.push_back(dev[i].m);
      double mu = 0;
      for (int k = 0; k < 5; ++k) mu += theta[static_cast<std::size_t>(k)] * noise_basis(k, dev[i].tau_s);
      l.push_back(std::log(dev[i].dev * dev[i].dev / mu));
    }
    lr.push_back(std::move(l));
    std::fprintf(stderr, "\r%s record %d/%d   ", s.name.c_str(), r + 1, seeds);
  }
  std::fprintf(stderr, "\n");
  const std::size_t P = tau.size();
  const LogScatter model = model_log_scatter(tau, m, theta, n + 1);
  auto C = [&](std::size_t i, std::size_t j) { return model.cov[i * P + j]; };
  std::vector<double> mean(P, 0), sd(P, 0);
  for (const auto& l : lr)
    for (std::size_t i = 0; i < P; ++i) mean[i] += l[i] / seeds;
  for (const auto& l : lr)
    for (std::size_t i = 0; i < P; ++i) sd[i] += (l[i] - mean[i]) * (l[i] - mean[i]) / (seeds - 1);
  for (double& v : sd) v = std::sqrt(v);
  std::string out = std::string("| tau (s) | mean ln(s/mu): measured | model | sd: measured | model | ratio | ") +
                    "corr with the previous point: measured | model |\n|---|---|---|---|---|---|---|---|\n";
  char line[256];
  for (std::size_t i = 0; i < P; ++i) {
    const double msd = std::sqrt(C(i, i));
    std::snprintf(line, sizeof line, "| %.4g | %+.3f | %+.3f | %.3f | %.3f | %.2f |", tau[i], mean[i], model.bias[i], sd[i], msd,
                  sd[i] / msd);
    out += line;
    if (i > 0) {
      double c = 0;
      for (const auto& l : lr) c += (l[i] - mean[i]) * (l[i - 1] - mean[i - 1]) / (seeds - 1);
      std::snprintf(line, sizeof line, " %.2f | %.2f |\n", c / (sd[i] * sd[i - 1]), C(i, i - 1) / std::sqrt(C(i, i) * C(i - 1, i - 1)));
    } else {
      std::snprintf(line, sizeof line, " | |\n");
    }
    out += line;
  }
  // GLS chi-square at the truth, residuals less the model's log bias: Cholesky of the covariance.
  std::vector<double> L(P * P, 0);  // lower triangle
  for (std::size_t i = 0; i < P; ++i)
    for (std::size_t j = 0; j <= i; ++j) {
      double v = C(i, j);
      for (std::size_t k = 0; k < j; ++k) v -= L[i * P + k] * L[j * P + k];
      L[i * P + j] = i == j ? std::sqrt(v) : v / L[j * P + j];
    }
  double chi2 = 0;
  for (const auto& l : lr) {
    std::vector<double> w(P);
    for (std::size_t i = 0; i < P; ++i) {
      double v = l[i] - model.bias[i];
      for (std::size_t k = 0; k < i; ++k) v -= L[i * P + k] * w[k];
      w[i] = v / L[i * P + i];
      chi2 += w[i] * w[i] / seeds;
    }
  }
  std::snprintf(line, sizeof line, "\n%s, %d records from seed %llu: mean GLS chi-square at the truth %.1f over %zu points\n",
                s.name.c_str(), seeds, base, chi2, P);
  return out + line;
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 20;
  unsigned long long base = 12000;
  bool ci = false;
  int pos = 0;
  bool covariance = false;
  std::string only;  // --set NAME: that parameter set alone (e.g. "R 6h")
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--ci")) ci = true;
    else if (!std::strcmp(argv[i], "--covariance")) covariance = true;
    else if (!std::strcmp(argv[i], "--set") && i + 1 < argc) only = argv[++i];
    else if (pos++ == 0) seeds = std::atoi(argv[i]);
    else base = std::strtoull(argv[i], nullptr, 10);
  }
  std::vector<Set> chosen = sets(ci);
  // A set run alone keeps its seeds (base + 1000 * its index + i).
  if (!only.empty()) {
    std::size_t k = 0;
    while (k < chosen.size() && chosen[k].name != only) ++k;
    if (k == chosen.size()) {
      std::fprintf(stderr, "coverage_noise: no set '%s'\n", only.c_str());
      return 2;
    }
    chosen = {chosen[k]};
    base += 1000 * k;
  }
  if (covariance) {
    if (only.empty()) {
      std::fprintf(stderr, "coverage_noise: --covariance needs --set NAME\n");
      return 2;
    }
    std::fputs(covariance_table(chosen.front(), seeds, base).c_str(), stdout);
    return 0;
  }
  const auto cells = run_coverage(chosen, seeds, base, true);
  std::printf("%d seeds per set from %llu%s\n\n%s", seeds, base, ci ? " (CI rates)" : "", coverage_table(cells).c_str());
  // Pooled as docs/analysis.md states it: over the model's terms Q, N, B(model), K, R; dominant
  // cells' bounds holding, injected non-dominant cells' upper limits holding, values > 3x off
  // with bounds excluding the truth.
  int dom = 0, dom_cov = 0, nd = 0, nd_up = 0, off3 = 0;
  for (const Cell& c : cells) {
    if (c.term == "B") continue;
    off3 += c.excluded_3x;
    if (c.dominant) dom += c.runs, dom_cov += c.covered;
    else if (c.injected) nd += c.runs, nd_up += c.upper_holds;
  }
  std::printf("\npooled (Q, N, B(model), K, R): dominant bounds hold %d/%d = %.1f %%; non-dominant upper limit holds "
              "%d/%d = %.0f %%; > 3x off with bounds excluding: %d\n",
              dom_cov, dom, 100.0 * dom_cov / std::max(1, dom), nd_up, nd, 100.0 * nd_up / std::max(1, nd), off3);
  return 0;
}
