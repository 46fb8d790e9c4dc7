// Every strict Stable32 table in tests/data/allan-reference (see its README): deviations to
// 5e-5 relative, 68.3 % bounds to 5e-4 and the identified alpha on every row, term counts
// exactly; the only rows left out are the named exceptions below.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>
#include <string_view>
#include <tuple>
#include <vector>

#include "analysis/allan.hpp"
#include "analysis/edf.hpp"
#include "reference_data.hpp"

namespace rig::analysis {
namespace {

using testing::read_table;
using testing::read_values;
using testing::ref_path;

struct Case {
  const char* table;
  const char* data;
  DataKind kind;
  double tau0;
  Deviation dev;
  bool check_alpha = true;   // tables computed with a fixed alpha print that alpha instead
  bool strict_bounds = true; // README: TOTDEV bounds on gps/ are not a strict reference
  std::optional<int> fixed_alpha = std::nullopt;  // the table was made with a chosen noise type
};

std::ostream& operator<<(std::ostream& o, const Case& c) { return o << c.table; }

// Rows whose printed alpha no Stable32 rule we know reproduces (docs/analysis.md, "Noise
// identification and bounds"). Their alpha is not compared, nor their bounds, which follow it.
struct Exception {
  const char* table;
  std::vector<std::size_t> afs;
  const char* why;
};
const Exception kExceptions[] = {
    // Lag-1 ACF rows (the only ACF exceptions in the 56 tables): the phase is non-stationary
    // here (rho >= 0.25), it is differenced once, and Stable32 prints an alpha one below the
    // ACF's; no rule found reproduces these nine.
    {"Keysight53230A/tic_adev.txt", {126, 190, 360, 408, 789, 890, 1004, 1370, 1824},
     "ACF on a non-stationary phase: Stable32 prints one alpha lower; unexplained"},
    // B1 gives 0.695 at AF 128 (< 0.82, phase modulation: alpha 1, as for AF 127 and 129 in
    // phase_dat_totdev.txt on the same data); Stable32 printed 0 and repeated it at AF 256.
    {"phasedat/phase_dat_totdev_octave.txt", {128, 256}, "Stable32 prints alpha 0 where its B1 rule gives 1"},
};

const Exception* exception_for(const char* table) {
  for (const Exception& e : kExceptions)
    if (std::string_view(e.table) == table) return &e;
  return nullptr;
}

// The data sets, loaded once (the Cs5071A set is 557k points).
const std::vector<double>& dataset(const std::string& rel) {
  static std::map<std::string, std::vector<double>> cache;
  auto it = cache.find(rel);
  if (it != cache.end()) return it->second;
  std::vector<double> v = read_values(ref_path(rel));
  if (rel == "ocxo/ocxo_frequency.txt")  // README: y = (f - 1e7) / 1e7
    for (double& x : v) x = (x - 1e7) / 1e7;
  return cache.emplace(rel, std::move(v)).first->second;
}

class Stable32Table : public ::testing::TestWithParam<Case> {};

TEST_P(Stable32Table, MatchesDeviationsBoundsTermsAlpha) {
  const Case& c = GetParam();
  const auto rows = read_table(ref_path(c.table));
  const auto& data = dataset(c.data);
  DevOptions o;
  o.type = c.dev;
  o.data = c.kind;
  o.rate_hz = 1.0 / c.tau0;
  // The header says "Confidence Factor = 0.683"; the bounds are Stable32's at the exact one
  // sigma, erf(1/sqrt 2) = 0.682689 (at 0.683 the EDF-3 rows' upper bounds are 5.6e-4 off).
  o.confidence = std::erf(1 / std::numbers::sqrt2);
  for (const auto& r : rows) o.factors.push_back(r.af);
  o.fixed_alpha = c.fixed_alpha;
  const auto pts = deviation(data, o);
  ASSERT_EQ(pts.size(), rows.size());

  const Exception* exc = exception_for(c.table);
  // Phase points and the averages each factor leaves (>= 30: lag-1 ACF, else B1/R(n)).
  const std::size_t n_phase = c.kind == DataKind::Frequency ? data.size() + 1 : data.size();
  int bad_dev = 0, bad_terms = 0, bad_alpha = 0, bad_bounds = 0, skipped = 0, capped = 0;
  int acf_rows = 0, acf_agree = 0, b1_rows = 0, b1_agree = 0;
  double worst_dev = 0, worst_bound = 0;
  std::ostringstream log;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    const auto& p = pts[i];
    const double e = std::abs(p.dev - r.dev) / r.dev;
    worst_dev = std::max(worst_dev, e);
    if (e > 5e-5) {
      ++bad_dev;
      log << "  AF " << r.af << " dev " << p.dev << " ref " << r.dev << " rel " << e << "\n";
    }
    if (p.n_terms != r.terms) {
      ++bad_terms;
      log << "  AF " << r.af << " terms " << p.n_terms << " ref " << r.terms << "\n";
    }
    const bool acf_row = (n_phase - 1) / r.af >= 30;
    (acf_row ? acf_rows : b1_rows) += 1;
    (acf_row ? acf_agree : b1_agree) += p.alpha == r.alpha;
    if (exc && std::find(exc->afs.begin(), exc->afs.end(), r.af) != exc->afs.end()) {
      ++skipped;
      if (p.alpha == r.alpha) std::printf("  %s AF %zu: excepted but agrees now, trim kExceptions\n", c.table, r.af);
      continue;
    }
    if (c.check_alpha && p.alpha != r.alpha) {
      ++bad_alpha;
      log << "  AF " << r.af << " alpha " << p.alpha << " ref " << r.alpha << "\n";
    }
    if (r.lo > 0 && c.strict_bounds) {
      // TOTDEV at small m: the rig's EDF is at most OADEV's times (N - 2) / (N - 2m) (edf.hpp),
      // below Stable32's Table 7 value; there the row is compared with the bounds Table 7's EDF
      // gives on the rig's deviation (Stable32's rule), and the rig's EDF must be the capped one.
      double lo = p.lo, hi = p.hi;
      // The same for the PM alphas, where Stable32 takes Table 5's simple forms (a review: flicker
      // PM's read 1.6x OADEV's EDF, bounds narrower than OADEV's at the same tau).
      if (c.dev == Deviation::TOTDEV && p.alpha <= 2 && p.alpha >= -2) {
        const double b[3] = {1.50, 1.17, 0.93}, cc[3] = {0.0, 0.22, 0.36};
        const double t7 = p.alpha > 0 ? edf_simple(n_phase, r.af, p.alpha)
                                      : b[-p.alpha] * static_cast<double>(n_phase) / static_cast<double>(r.af) - cc[-p.alpha];
        if (p.edf < t7 * (1 - 1e-12)) {
          ++capped;
          EXPECT_NEAR(p.edf, edf_greenhall(p.alpha, 2, r.af, n_phase, true, false) * (static_cast<double>(n_phase) - 2) /
                                 (static_cast<double>(n_phase) - 2.0 * static_cast<double>(r.af)),
                      1e-9 * p.edf)
              << c.table << " AF " << r.af;
          std::tie(lo, hi) = chi2_bounds(p.dev, t7, o.confidence);
        }
      }
      const double el = std::abs(lo - r.lo) / r.lo, eh = std::abs(hi - r.hi) / r.hi;
      worst_bound = std::max({worst_bound, el, eh});
      if (el > 5e-4 || eh > 5e-4) {
        ++bad_bounds;
        log << "  AF " << r.af << " lo " << p.lo << " ref " << r.lo << " hi " << p.hi << " ref " << r.hi
            << " edf " << p.edf << "\n";
      }
    }
  }
  // Every row: values, term counts, alpha and (where printed) bounds; only kExceptions are skipped.
  EXPECT_TRUE(bad_dev == 0 && bad_terms == 0 && bad_alpha == 0 && bad_bounds == 0)
      << c.table << ": " << bad_dev << " deviations, " << bad_terms << " term counts, " << bad_alpha << " alphas, "
      << bad_bounds << " bounds off (worst dev " << worst_dev << ", worst bound " << worst_bound << ")\n"
      << log.str().substr(0, 3000);
  RecordProperty("worst_dev_rel", std::to_string(worst_dev));
  RecordProperty("totdev_rows_capped", std::to_string(capped));
  RecordProperty("worst_bound_rel", std::to_string(worst_bound));
  RecordProperty("b1_alpha_agreement", std::to_string(b1_agree) + "/" + std::to_string(b1_rows));
  std::printf("%-40s worst dev %.2e, worst bound %.2e, ACF-region alpha %d/%d, B1-region alpha %d/%d%s\n", c.table,
              worst_dev, worst_bound, acf_agree, acf_rows, b1_agree, b1_rows,
              skipped ? (", " + std::to_string(skipped) + " excepted rows (" + exc->why + ")").c_str() : "");
}

constexpr auto F = DataKind::Frequency;
constexpr auto P = DataKind::Phase;
using D = Deviation;

const Case kCases[] = {
    {"phasedat/phase_dat_adev.txt", "phasedat/PHASE.DAT", P, 1, D::ADEV},
    {"phasedat/phase_dat_adev_octave.txt", "phasedat/PHASE.DAT", P, 1, D::ADEV},
    {"phasedat/phase_dat_oadev.txt", "phasedat/PHASE.DAT", P, 1, D::OADEV},
    {"phasedat/phase_dat_oadev_octave.txt", "phasedat/PHASE.DAT", P, 1, D::OADEV},
    {"phasedat/phase_dat_mdev.txt", "phasedat/PHASE.DAT", P, 1, D::MDEV},
    {"phasedat/phase_dat_mdev_octave.txt", "phasedat/PHASE.DAT", P, 1, D::MDEV},
    {"phasedat/phase_dat_tdev.txt", "phasedat/PHASE.DAT", P, 1, D::TDEV},
    {"phasedat/phase_dat_tdev_octave.txt", "phasedat/PHASE.DAT", P, 1, D::TDEV},
    {"phasedat/phase_dat_hdev.txt", "phasedat/PHASE.DAT", P, 1, D::HDEV},
    {"phasedat/phase_dat_hdev_octave.txt", "phasedat/PHASE.DAT", P, 1, D::HDEV},
    {"phasedat/phase_dat_ohdev.txt", "phasedat/PHASE.DAT", P, 1, D::OHDEV},
    {"phasedat/phase_dat_ohdev_octave.txt", "phasedat/PHASE.DAT", P, 1, D::OHDEV},
    {"phasedat/phase_dat_totdev.txt", "phasedat/PHASE.DAT", P, 1, D::TOTDEV},
    {"phasedat/phase_dat_totdev_octave.txt", "phasedat/PHASE.DAT", P, 1, D::TOTDEV},
    {"pink_frequency/adev.txt", "pink_frequency/pink_frequency.txt", F, 42, D::ADEV},
    {"pink_frequency/oadev.txt", "pink_frequency/pink_frequency.txt", F, 42, D::OADEV},
    {"pink_frequency/mdev.txt", "pink_frequency/pink_frequency.txt", F, 42, D::MDEV},
    {"pink_frequency/tdev.txt", "pink_frequency/pink_frequency.txt", F, 42, D::TDEV},
    {"pink_frequency/hdev.txt", "pink_frequency/pink_frequency.txt", F, 42, D::HDEV},
    {"pink_frequency/ohdev.txt", "pink_frequency/pink_frequency.txt", F, 42, D::OHDEV},
    {"pink_frequency/totdev_alpha0.txt", "pink_frequency/pink_frequency.txt", F, 42, D::TOTDEV, true, true, 0},
    {"pink_frequency/s32_oadev_octave.txt", "pink_frequency/pink_frequency.txt", F, 1, D::OADEV},
    {"ocxo/stable32_adev_alltau.txt", "ocxo/ocxo_frequency.txt", F, 1, D::ADEV},
    {"ocxo/stable32_oadev_alltau.txt", "ocxo/ocxo_frequency.txt", F, 1, D::OADEV},
    {"ocxo/stable32_mdev_alltau.txt", "ocxo/ocxo_frequency.txt", F, 1, D::MDEV},
    {"ocxo/stable32_tdev_alltau.txt", "ocxo/ocxo_frequency.txt", F, 1, D::TDEV},
    {"ocxo/stable32_hdev_alltau.txt", "ocxo/ocxo_frequency.txt", F, 1, D::HDEV},
    {"ocxo/stable32_ohdev_alltau.txt", "ocxo/ocxo_frequency.txt", F, 1, D::OHDEV},
    {"gps/stable32_ADEV_decade.txt", "gps/gps_1pps_phase_data.txt.gz", P, 1, D::ADEV},
    {"gps/stable32_OADEV_octave.txt", "gps/gps_1pps_phase_data.txt.gz", P, 1, D::OADEV},
    {"gps/stable32_MDEV_octave.txt", "gps/gps_1pps_phase_data.txt.gz", P, 1, D::MDEV},
    {"gps/stable32_TDEV_octave.txt", "gps/gps_1pps_phase_data.txt.gz", P, 1, D::TDEV},
    {"gps/stable32_HDEV_octave.txt", "gps/gps_1pps_phase_data.txt.gz", P, 1, D::HDEV},
    {"gps/stable32_OHDEV_octave.txt", "gps/gps_1pps_phase_data.txt.gz", P, 1, D::OHDEV},
    {"gps/stable32_TOTDEV_octave.txt", "gps/gps_1pps_phase_data.txt.gz", P, 1, D::TOTDEV, true, false},
    {"Cs5071A/adev_all.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::ADEV},
    {"Cs5071A/adev_decade.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::ADEV},
    {"Cs5071A/oadev_all.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::OADEV},
    {"Cs5071A/oadev_decade.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::OADEV},
    {"Cs5071A/mdev_all.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::MDEV},
    {"Cs5071A/mdev_decade.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::MDEV},
    {"Cs5071A/tdev_all.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::TDEV},
    {"Cs5071A/tdev_decade.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::TDEV},
    {"Cs5071A/hdev_all.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::HDEV},
    {"Cs5071A/hdev_decade.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::HDEV},
    {"Cs5071A/ohdev_all.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::OHDEV},
    {"Cs5071A/ohdev_decade.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::OHDEV},
    {"Cs5071A/totdev_all.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::TOTDEV},
    // Every row says alpha 0 and its bounds are the alpha-0 ones: made with white FM chosen.
    {"Cs5071A/totdev_decade.txt", "Cs5071A/5071A_phase.txt.gz", P, 1, D::TOTDEV, true, true, 0},
    {"Keysight53230A/tic_adev.txt", "Keysight53230A/tic_phase.txt", P, 1, D::ADEV},
    {"Keysight53230A/tic_oadev.txt", "Keysight53230A/tic_phase.txt", P, 1, D::OADEV},
    {"Keysight53230A/tic_mdev.txt", "Keysight53230A/tic_phase.txt", P, 1, D::MDEV},
    {"Keysight53230A/tic_tdev.txt", "Keysight53230A/tic_phase.txt", P, 1, D::TDEV},
    {"Keysight53230A/tic_hdev.txt", "Keysight53230A/tic_phase.txt", P, 1, D::HDEV},
    {"Keysight53230A/tic_ohdev.txt", "Keysight53230A/tic_phase.txt", P, 1, D::OHDEV},
    {"Keysight53230A/tic_totdev.txt", "Keysight53230A/tic_phase.txt", P, 1, D::TOTDEV},
};

std::string case_name(const ::testing::TestParamInfo<Case>& info) {
  std::string s = info.param.table;
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
}

INSTANTIATE_TEST_SUITE_P(Stable32, Stable32Table, ::testing::ValuesIn(kCases), case_name);

}  // namespace
}  // namespace rig::analysis
