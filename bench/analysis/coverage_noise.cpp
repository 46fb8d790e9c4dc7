// Coverage of the noise-term bounds over injected-noise records (tests/analysis/injected_noise.hpp):
//   coverage_noise [SEEDS=20] [BASE_SEED=12000] [--ci] [--set NAME]
//   coverage_noise --theo1-moments [RECORDS=600]
// prints the Markdown coverage table of docs/analysis.md. Full size: 1 h at 1 kHz, 6 h at
// 100 Hz, 60 h at 10 Hz (about 5 min on the 2-core rig PC for 20 seeds); --ci: the test's
// rates (10x lower). --theo1-moments: the log-scale moments of the fit's Theo1 points
// (analysis/long_tau_fit.hpp) per noise term, by simulation: the tables in long_tau_fit.cpp.
#include <algorithm>
#include <boost/math/special_functions/digamma.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "analysis/long_tau_fit.hpp"
#include "analysis/noise_model.hpp"
#include "tests/analysis/noise_coverage.hpp"

namespace {

using namespace rig::analysis;

// The EDF nu whose E[ln(chi2_nu/nu)] = digamma(nu/2) - ln(nu/2) is `mean` (< 0), by bisection.
double nu_of_log_mean(double mean) {
  double lo = 0.05, hi = 1e6;
  for (int i = 0; i < 200; ++i) {
    const double mid = std::sqrt(lo * hi);
    (boost::math::digamma(mid / 2) - std::log(mid / 2) < mean ? lo : hi) = mid;
  }
  return std::sqrt(lo * hi);
}

double corr(const std::vector<double>& a, const std::vector<double>& b) {
  const double n = static_cast<double>(a.size());
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) ma += a[i] / n, mb += b[i] / n;
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

// Per term alone (Q, N, B, K) and record length: ln(s/E) of the two Theo1 points (E the model's
// expectation: basis x factor), its mean and variance, the EDFs they imply, and the correlation
// with ln OADEV^2 at m = (N-1)/4 (the fit's last OADEV point on log:N) and (N-1)/8.
int theo1_moments(int records) {
  const injected::Terms unit[4] = {{1e-6, 0, 0, 0, 0}, {0, 1e-5, 0, 0, 0}, {0, 0, 1e-6, 0, 0}, {0, 0, 0, 1e-7, 0}};
  const char* names[4] = {"Q", "N", "B", "K"};
  const double rate = 10;
  std::printf("| term | n | stride | tau/T | mean s/E | mean ln(s/E) | var ln(s/E) | nu_var = 2/var | nu_mean | corr OADEV T/4 | corr OADEV T/8 | corr T/2 vs 0.75T |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  const bool terms = !std::getenv("COVERAGE_SKIP_TERMS");  // the mixtures and the cross term only
  for (const std::size_t n : {20000u, 200000u})
    for (int k = 0; k < 4 && terms; ++k) {
      std::vector<double> l[2], a4, a8, ratio[2];
      std::size_t stride = 0;
      for (int r = 0; r < records; ++r) {
        const auto y = injected::generate(unit[k], rate, n, 50000 + 7919ull * static_cast<unsigned>(r) + 131ull * n + static_cast<unsigned>(k));
        const auto pts = theo1_fit_points(y, DataKind::Frequency, rate);
        if (pts.size() != 2) return 1;
        stride = pts[0].stride;
        for (int q = 0; q < 2; ++q) {
          const double e = injected::term_avar(unit[k], k, pts[q].tau_s) * pts[q].factor[static_cast<std::size_t>(k)];
          ratio[q].push_back(pts[q].var / e);
          l[q].push_back(std::log(pts[q].var / e));
        }
        DevOptions o;
        o.rate_hz = rate;
        o.bounds = false;
        o.factors = {n / 4, n / 8};
        const auto d = deviation(y, o);
        if (d.size() != 2) return 1;
        const DevPoint& d4 = d[0].m == n / 4 ? d[0] : d[1];
        const DevPoint& d8 = d[0].m == n / 4 ? d[1] : d[0];
        a4.push_back(std::log(d4.dev * d4.dev));
        a8.push_back(std::log(d8.dev * d8.dev));
      }
      const double c12 = corr(l[0], l[1]);
      for (int q = 0; q < 2; ++q) {
        double mr = 0, m = 0, v = 0;
        for (double x : ratio[q]) mr += x / records;
        for (double x : l[q]) m += x / records;
        for (double x : l[q]) v += (x - m) * (x - m) / (records - 1);
        std::printf("| %s | %zu | %zu | %.2f | %.3f | %.3f | %.3f | %.2f | %.2f | %.2f | %.2f | %.2f |\n", names[k], n, stride,
                    kTheo1Fractions[static_cast<std::size_t>(q)], mr, m, v, 2 / v, nu_of_log_mean(m), corr(l[q], a4), corr(l[q], a8), c12);
      }
      std::fflush(stdout);
    }
  // The mixtures where the ramp dominates the Theo1 points (the R sets at CI rates): the measured
  // log-scale moments against what the fit claims from the true terms (theo1_model_edf: the
  // per-term EDFs above mixed, the ramp's exact cross term).
  std::printf("\n| set | tau/T | R share | mean ln(s/E) | claimed | var ln(s/E) | claimed 2/nu | random part | ramp cross part | f | corr OADEV T/4 | claimed | corr T/2 vs 0.75 T |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  const bool all_sets = std::getenv("COVERAGE_ALL_SETS");  // every set, not only the R sets
  for (const injected::Set& set : injected::sets(true)) {
    if (set.truth.R == 0 && !all_sets) continue;
    const std::size_t n = static_cast<std::size_t>(set.hours * 3600 * set.rate_hz);
    std::vector<double> l[2], la, la8;
    std::vector<LongTauFitPoint> last;
    const std::size_t ma = n / 4;
    const double tau_a = static_cast<double>(ma) / set.rate_hz;
    for (int r = 0; r < records / 3; ++r) {
      const auto y = injected::generate(set.truth, set.rate_hz, n, 70000 + static_cast<unsigned>(r));
      last = theo1_fit_points(y, DataKind::Frequency, set.rate_hz);
      DevOptions o;
      o.rate_hz = set.rate_hz;
      o.bounds = false;
      o.factors = {ma / 2, ma};
      const auto d = deviation(y, o);
      if (d.size() != 2) return 1;
      la8.push_back(std::log(d[0].dev * d[0].dev));
      la.push_back(std::log(d[1].dev * d[1].dev / injected::model_avar(set.truth, tau_a)));
      for (std::size_t q = 0; q < 2; ++q) {
        double e = 0;
        for (int k = 0; k < 5; ++k) e += injected::term_avar(set.truth, k, last[q].tau_s) * last[q].factor[static_cast<std::size_t>(k)];
        l[q].push_back(std::log(last[q].var / e));
      }
    }
    // The OADEV chain itself: ln OADEV^2 at T/8 against T/4, measured and as the fit claims it
    // (noise_model.cpp's one-octave correlations mixed by term_scatter; the ramp's as random walk's).
    {
      std::array<double, 5> m4{}, m8{};
      for (int k = 0; k < 5; ++k) {
        m4[static_cast<std::size_t>(k)] = injected::term_avar(set.truth, k, tau_a);
        m8[static_cast<std::size_t>(k)] = injected::term_avar(set.truth, k, tau_a / 2);
      }
      const std::array<double, 5> s4 = term_scatter(m4, ma, n + 1), s8 = term_scatter(m8, ma / 2, n + 1);
      static const double kOct1[5] = {0.41, 0.51, 0.66, 0.88, 0.88};
      double c = 0, n4 = 0, n8 = 0;
      for (std::size_t k = 0; k < 5; ++k) c += s4[k] * s8[k] * kOct1[k], n4 += s4[k] * s4[k], n8 += s8[k] * s8[k];
      std::printf("| %s | OADEV T/8 vs T/4 | | | | | | | | | %.2f | %.2f | |\n", set.name.c_str(), corr(la, la8), c / std::sqrt(n4 * n8));
    }
    for (std::size_t q = 0; q < 2; ++q) {
      std::array<double, 5> mu{};
      for (int k = 0; k < 5; ++k)
        mu[static_cast<std::size_t>(k)] = injected::term_avar(set.truth, k, last[q].tau_s) * last[q].factor[static_cast<std::size_t>(k)];
      const double tot = mu[0] + mu[1] + mu[2] + mu[3] + mu[4];
      const double nv = theo1_model_edf(mu, last[q].frac, last[q].ramp_cross), nm = theo1_model_edf(mu, last[q].frac, last[q].ramp_cross, true);
      double m = 0, v = 0;
      const double cnt = static_cast<double>(l[q].size());
      for (double x : l[q]) m += x / cnt;
      for (double x : l[q]) v += (x - m) * (x - m) / (cnt - 1);
      // The claimed variance's parts: the random terms' (their sds added) and the ramp's cross
      // term; f: the factor on the cross term's variance that would match the measured variance.
      const std::array<double, 5> sd = theo1_scatter(mu, last[q].frac, last[q].ramp_cross);
      const double vr = std::pow((sd[0] + sd[1] + sd[2] + sd[3]) / tot, 2), vc = std::pow(sd[4] / tot, 2);
      std::array<double, 5> mua{};
      for (int k = 0; k < 5; ++k) mua[static_cast<std::size_t>(k)] = injected::term_avar(set.truth, k, tau_a);
      const std::array<double, 5> sa = term_scatter(mua, ma, n + 1);
      double cab = 0, na = 0, nt = 0;
      for (std::size_t k = 0; k < 5; ++k) {
        cab += sd[k] * sa[k] * (k == 4 ? theo1_ramp_corr_oadev(last[q].frac) : theo1_corr_oadev(static_cast<int>(std::min<std::size_t>(k, 3)), last[q].frac));
        na += sa[k] * sa[k], nt += sd[k] * sd[k];
      }
      std::printf("| %s | %.2f | %.2f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f | %.2f | %.2f | %.2f |\n", set.name.c_str(), last[q].frac,
                  mu[4] / tot, m, boost::math::digamma(nm / 2) - std::log(nm / 2), v, 2 / nv, vr, vc, vc > 0 ? (v - vr) / vc : 0.0,
                  corr(l[q], la), cab / std::sqrt(na * nt), corr(l[0], l[1]));
    }
    std::fflush(stdout);
  }
  // The ramp's cross term alone: C = Theo1(ramp + noise) - Theo1(noise) - Theo1(ramp) (a
  // quadratic form; the generator adds the ramp last, so the same seed without R is the noise
  // alone), its variance over E_R E_k against LongTauFitPoint::ramp_cross, per term.
  std::printf("\n| noise term | tau/T | var(C)/(E_R E_k) measured | ramp_cross |\n|---|---|---|---|\n");
  for (int k = 0; k < 4; ++k) {
    const injected::Terms noise = unit[k];
    injected::Terms with = noise;
    with.R = 1e-9;
    const std::size_t n = 20000;
    std::vector<double> c[2];
    std::vector<LongTauFitPoint> pr;
    {
      const injected::Terms ramp{0, 0, 0, 0, 1e-9};
      pr = theo1_fit_points(injected::generate(ramp, rate, n, 1), DataKind::Frequency, rate);
    }
    std::vector<LongTauFitPoint> pw, pn;
    for (int r = 0; r < records / 3; ++r) {
      pw = theo1_fit_points(injected::generate(with, rate, n, 90000 + static_cast<unsigned>(r)), DataKind::Frequency, rate);
      pn = theo1_fit_points(injected::generate(noise, rate, n, 90000 + static_cast<unsigned>(r)), DataKind::Frequency, rate);
      for (std::size_t q = 0; q < 2; ++q) c[q].push_back(pw[q].var - pn[q].var - pr[q].var);
    }
    for (std::size_t q = 0; q < 2; ++q) {
      double v = 0;
      for (double x : c[q]) v += x * x / static_cast<double>(c[q].size());
      const double ek = injected::term_avar(noise, k, pr[q].tau_s) * pr[q].factor[static_cast<std::size_t>(k)];
      std::printf("| %s | %.2f | %.3f | %.3f |\n", names[k], pr[q].frac, v / (pr[q].var * ek), pr[q].ramp_cross[static_cast<std::size_t>(k)]);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && !std::strcmp(argv[1], "--theo1-moments")) return theo1_moments(argc >= 3 ? std::atoi(argv[2]) : 600);
  int seeds = 20;
  unsigned long long base = 12000;
  bool ci = false;
  int pos = 0;
  std::string only;  // --set NAME: that parameter set alone (e.g. "R 6h")
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--ci")) ci = true;
    else if (!std::strcmp(argv[i], "--set") && i + 1 < argc) only = argv[++i];
    else if (pos++ == 0) seeds = std::atoi(argv[i]);
    else base = std::strtoull(argv[i], nullptr, 10);
  }
  using namespace rig::analysis::injected;
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
