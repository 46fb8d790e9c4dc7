// Coverage of the noise-term bounds over injected-noise records (injected_noise.hpp): for each
// parameter set and term, how often the stated bounds hold the injected truth. Test code,
// shared by tests/analysis/test_noise_coverage.cpp (CI-sized) and bench/analysis (larger).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "analysis/allan.hpp"
#include "analysis/noise_model.hpp"
#include "analysis/noise_terms.hpp"
#include "tests/analysis/injected_noise.hpp"

namespace rig::analysis::injected {

struct Set {
  std::string name;
  Terms truth;
  double rate_hz = 1000, hours = 1;
};

// The paper's figures in seconds units: N = 2.2306e-7 g*h^0.5, K = 5.1167e-6 g/h^0.5, B ~2.1e-6 g.
inline constexpr double kPaperN = 2.2306e-7 * 60, kPaperK = 5.1167e-6 / 60, kPaperB = 2.1e-6;

// The parameter sets (fixed before any result was looked at). `ci` lowers the rate by 10
// (the same record duration, so the same terms dominate over the same tau range, 10x fewer samples).
inline std::vector<Set> sets(bool ci) {
  std::vector<Set> v;
  // Q then N dominate (Q below 0.05 s); B and K present but never dominate.
  v.push_back({"QN 1h", {1.73e-6, kPaperN, 2e-7, 1e-8, 0}, 1000, 1});
  // B dominates 16..900 s; N below; K present, never dominates.
  v.push_back({"B 1h", {0, kPaperN, 5e-6, kPaperK, 0}, 1000, 1});
  // K dominates from 77 s within 1 h; B present, never dominates.
  v.push_back({"K 1h", {0, kPaperN, 3e-7, 3e-7, 0}, 1000, 1});
  // R dominates from 1000 s on 6 h (the paper's N, K; small B).
  v.push_back({"R 6h", {0, kPaperN, 1e-6, kPaperK, kPaperK * std::sqrt(2.0 / 3000)}, 100, 6});
  // R dominates from 10000 s on 60 h.
  v.push_back({"R 60h", {0, kPaperN, 1e-6, kPaperK, kPaperK * std::sqrt(2.0 / 30000)}, 10, 60});
  // Mixed, the paper's N, B, K with a quantisation Q, 1 h.
  v.push_back({"mixed 1h", {1e-6, kPaperN, kPaperB, kPaperK, 0}, 1000, 1});
  if (ci)
    for (Set& s : v) s.rate_hz /= 10;
  return v;
}

struct Cell {
  std::string set, term;
  bool dominant = false, injected = false;
  int runs = 0, reported = 0, covered = 0, null_ = 0, upper = 0, upper_holds = 0, false_pos = 0;
  int null_held = 0;  // nulls whose upper limit holds the truth (a null's interval is [0, limit])
  int excluded_3x = 0;
  std::vector<double> ratios;  // value/truth where reported
  double worst_excluded = 1;   // value/truth farthest from 1 (in log) with bounds excluding the truth
};

// One record's terms as the rig reports them (B: the passport's, the paper method) plus the
// least-squares B.
struct Reported {
  const char* name;
  int k;  // truth index
  Term t;
};
inline std::vector<Reported> reported_terms(const NoiseTerms& nt) {
  return {{"Q", 0, nt.Q}, {"N", 1, nt.N}, {"B", 2, nt.B}, {"B(model)", 2, nt.wls.B}, {"K", 3, nt.K}, {"R", 4, nt.R}};
}

inline void score(Cell& c, const Term& t, double truth) {
  ++c.runs;
  if (!t.value) {
    ++c.null_;
    if (t.hi) {
      ++c.upper;
      if (*t.hi >= truth) ++c.upper_holds, ++c.null_held;
    }
    return;
  }
  ++c.reported;
  if (t.hi) {
    ++c.upper;
    if (*t.hi >= truth) ++c.upper_holds;
  }
  if (truth <= 0) {
    if (t.lo && *t.lo > 0) ++c.false_pos;
    return;
  }
  const double r = *t.value / truth;
  c.ratios.push_back(r);
  const bool holds = t.lo && t.hi && *t.lo <= truth && truth <= *t.hi;
  if (holds) ++c.covered;
  else {
    if (std::abs(std::log(r)) > std::abs(std::log(c.worst_excluded))) c.worst_excluded = r;
    if (r > 3 || r < 1.0 / 3) ++c.excluded_3x;
  }
}

// Runs `seeds` seeds of each set (seed = base + 1000 * set index + i) and returns the cells.
// per_record (bench): one line per record and term, "set<TAB>seed<TAB>term<TAB>truth<TAB>value<TAB>
// lo<TAB>hi" (a null's value and lo "-", its hi the upper limit or "-"), to take a cell apart.
inline std::vector<Cell> run_coverage(const std::vector<Set>& sets, int seeds, std::uint64_t base,
                                      bool progress = false, std::FILE* per_record = nullptr,
                                      double confidence = kOneSigma) {
  std::vector<Cell> cells;
  for (std::size_t si = 0; si < sets.size(); ++si) {
    const Set& s = sets[si];
    const auto n = static_cast<std::size_t>(s.hours * 3600 * s.rate_hz);
    std::vector<Cell> sc;
    for (int i = 0; i < seeds; ++i) {
      const std::vector<double> y = generate(s.truth, s.rate_hz, n, base + 1000 * si + static_cast<std::uint64_t>(i));
      DevOptions opt;
      opt.rate_hz = s.rate_hz;
      opt.taus = parse_tau_grid("log:100");
      const std::vector<DevPoint> dev = deviation(y, opt);
      const NoiseTerms nt = noise_terms(dev, static_cast<double>(n) / s.rate_hz, kRMinRecordS, least_squares_drift(y, s.rate_hz), confidence);
      const auto rep = reported_terms(nt);
      if (sc.empty())
        for (const auto& r : rep) {
          Cell c;
          c.set = s.name;
          c.term = r.name;
          c.injected = s.truth.at(r.k) > 0;
          const double total_share = 0.5;
          for (const DevPoint& p : dev)
            if (term_avar(s.truth, r.k, p.tau_s) >= total_share * model_avar(s.truth, p.tau_s)) c.dominant = true;
          sc.push_back(c);
        }
      for (std::size_t j = 0; j < rep.size(); ++j) score(sc[j], rep[j].t, s.truth.at(rep[j].k));
      if (per_record)
        for (const auto& r : rep) {
          auto num = [](const std::optional<double>& v) {
            char b[32] = "-";
            if (v) std::snprintf(b, sizeof b, "%.17g", *v);
            return std::string(b);
          };
          std::fprintf(per_record, "%s\t%llu\t%s\t%.17g\t%s\t%s\t%s\n", s.name.c_str(),
                       static_cast<unsigned long long>(base + 1000 * si + static_cast<std::uint64_t>(i)), r.name,
                       s.truth.at(r.k), num(r.t.value).c_str(), num(r.t.lo).c_str(), num(r.t.hi).c_str());
        }
      if (progress) std::fprintf(stderr, "\r%s seed %d/%d   ", s.name.c_str(), i + 1, seeds);
    }
    cells.insert(cells.end(), sc.begin(), sc.end());
  }
  if (progress) std::fprintf(stderr, "\n");
  return cells;
}

inline double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : (v[h - 1] + v[h]) / 2;
}

// A Markdown table: dominant terms: coverage of the stated bounds; non-dominant: null or an
// upper limit that holds; every reported value: median value/truth, worst ratio with the
// bounds excluding the truth, and how many of those are off by more than 3x.
inline std::string coverage_table(const std::vector<Cell>& cells) {
  std::string out =
      "| set | term | injected | dominant | runs | reported | bounds hold truth | null | upper limit holds | "
      "median value/truth | worst value/truth, bounds excluding | excluded > 3x |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  char buf[512];
  for (const Cell& c : cells) {
    const double med = median(c.ratios);
    std::snprintf(buf, sizeof buf, "| %s | %s | %s | %s | %d | %d | %d/%d (%.0f %%) | %d | %d/%d | %s | %s | %d |\n",
                  c.set.c_str(), c.term.c_str(), c.injected ? "yes" : "no", c.dominant ? "yes" : "no", c.runs,
                  c.reported, c.covered, c.runs, 100.0 * c.covered / std::max(1, c.runs), c.null_, c.upper_holds,
                  c.runs, std::isnan(med) ? "-" : (std::to_string(med).substr(0, 5)).c_str(),
                  c.worst_excluded == 1 ? "-" : std::to_string(c.worst_excluded).substr(0, 6).c_str(),
                  c.excluded_3x);
    out += buf;
  }
  return out;
}

// What the noise fit assumes of its points (model_log_scatter at the true terms: mean and
// covariance of ln s_i) against `records` simulated records of the set (seeds base + i): per
// octave point the measured and assumed mean of ln(s_i / mu_i), sd, correlation with the previous
// point; and the records' mean GLS chi-square at the truth on the assumed covariance (the number
// of points when the assumption is right).
struct ScatterCheck {
  std::vector<double> tau, mean, sd, corr_prev;  // measured (corr_prev[0] = 0)
  LogScatter model;                              // assumed
  double chi2 = 0;                               // mean over the records
  std::size_t points() const { return tau.size(); }
  double model_sd(std::size_t i) const { return std::sqrt(model.cov[i * points() + i]); }
  double model_corr_prev(std::size_t i) const {
    const std::size_t P = points();
    return i ? model.cov[i * P + i - 1] / std::sqrt(model.cov[i * P + i] * model.cov[(i - 1) * P + i - 1]) : 0;
  }
};

inline ScatterCheck check_log_scatter(const Set& s, int records, std::uint64_t base, bool progress = false) {
  const auto n = static_cast<std::size_t>(s.hours * 3600 * s.rate_hz);
  std::array<double, 5> theta{};
  for (int k = 0; k < 5; ++k) theta[static_cast<std::size_t>(k)] = s.truth.at(k) * s.truth.at(k);
  ScatterCheck c;
  std::vector<std::size_t> m;
  std::vector<std::vector<double>> lr;  // per record, ln(s_i / mu_i)
  for (int r = 0; r < records; ++r) {
    const std::vector<double> y = generate(s.truth, s.rate_hz, n, base + static_cast<std::uint64_t>(r));
    DevOptions opt;
    opt.rate_hz = s.rate_hz;
    opt.taus = parse_tau_grid("log:100");
    opt.bounds = false;
    const std::vector<DevPoint> dev = deviation(y, opt);
    c.tau.clear(), m.clear();
    std::vector<double> l;
    for (const std::size_t i : octave_points(dev)) {
      c.tau.push_back(dev[i].tau_s);
      m.push_back(dev[i].m);
      l.push_back(std::log(dev[i].dev * dev[i].dev / model_avar(s.truth, dev[i].tau_s)));
    }
    lr.push_back(std::move(l));
    if (progress) std::fprintf(stderr, "\r%s record %d/%d   ", s.name.c_str(), r + 1, records);
  }
  if (progress) std::fprintf(stderr, "\n");
  const std::size_t P = c.tau.size();
  c.model = model_log_scatter(c.tau, m, theta, n + 1);
  c.mean.assign(P, 0), c.sd.assign(P, 0), c.corr_prev.assign(P, 0);
  const double R = records;
  for (const auto& l : lr)
    for (std::size_t i = 0; i < P; ++i) c.mean[i] += l[i] / R;
  for (const auto& l : lr)
    for (std::size_t i = 0; i < P; ++i) {
      c.sd[i] += (l[i] - c.mean[i]) * (l[i] - c.mean[i]) / (R - 1);
      if (i) c.corr_prev[i] += (l[i] - c.mean[i]) * (l[i - 1] - c.mean[i - 1]) / (R - 1);
    }
  for (std::size_t i = 0; i < P; ++i) c.sd[i] = std::sqrt(c.sd[i]);
  for (std::size_t i = 1; i < P; ++i) c.corr_prev[i] /= c.sd[i] * c.sd[i - 1];
  // chi-square at the truth: the residuals less the assumed bias, whitened by the Cholesky factor.
  std::vector<double> L(P * P, 0);
  for (std::size_t i = 0; i < P; ++i)
    for (std::size_t j = 0; j <= i; ++j) {
      double v = c.model.cov[i * P + j];
      for (std::size_t k = 0; k < j; ++k) v -= L[i * P + k] * L[j * P + k];
      L[i * P + j] = i == j ? std::sqrt(v) : v / L[j * P + j];
    }
  for (const auto& l : lr) {
    std::vector<double> w(P);
    for (std::size_t i = 0; i < P; ++i) {
      double v = l[i] - c.model.bias[i];
      for (std::size_t k = 0; k < i; ++k) v -= L[i * P + k] * w[k];
      w[i] = v / L[i * P + i];
      c.chi2 += w[i] * w[i] / R;
    }
  }
  return c;
}

}  // namespace rig::analysis::injected
