// Prints the calibration table of an emulated DUT profile: the paper's procedure
// run on the model and evaluated by the rig's own analysis (docs/plant.md).
//   dut_calibrate [overrides.toml] [--seed N]... [--taus GRID] [--curves]
// Several --seed give one column per seed (each a full 110 min procedure).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "plant/dut/loop_figures.hpp"
#include "analysis/noise_terms.hpp"
#include "rig/core/toml_util.hpp"
#include "tests/plant/paper_procedure.hpp"

using namespace rig::plant;

namespace {
double val(const rig::analysis::Term& t) { return t.value ? *t.value : std::nan(""); }

// "v [lo, hi]" of a WLS term in passport units, or its reason.
std::string term(const rig::analysis::Term& t, double scale) {
  char b[128];
  if (!t.value) return "null (" + t.reason + ")";
  std::snprintf(b, sizeof b, "%.3e [%.3e, %.3e]", *t.value * scale, t.lo.value_or(NAN) * scale,
                t.hi.value_or(NAN) * scale);
  return b;
}
}  // namespace

int main(int argc, char** argv) {
  try {
    toml::table over;
    std::vector<uint64_t> seeds;
    calib::Spec spec;
    bool curves = false;
    for (int i = 1; i < argc; ++i) {
      if (!std::strcmp(argv[i], "--seed") && i + 1 < argc) seeds.push_back(std::stoull(argv[++i]));
      else if (!std::strcmp(argv[i], "--taus") && i + 1 < argc) spec.taus = argv[++i];
      else if (!std::strcmp(argv[i], "--curves")) curves = true;
      else over = rig::cfg::parse_file(argv[i]);
    }
    if (seeds.empty()) seeds.push_back(1);
    const DutParams p = load_dut_params(&over);
    std::vector<calib::Result> rs;
    for (uint64_t s : seeds) {
      EmulatedDut dut(p, s);
      rs.push_back(calib::run(dut, spec));
    }
    const rig::design::LoopFigures lf = loop_figures(&over, p.filter);
    namespace A = rig::analysis;
    auto row = [&](const char* name, const char* paper, auto f) {
      std::printf("| %s | %s |", name, paper);
      for (const auto& r : rs) std::printf(" %s |", f(r).c_str());
      std::printf("\n");
    };
    auto num = [](const char* fmt, double v) {
      char b[64];
      std::snprintf(b, sizeof b, fmt, v);
      return std::string(b);
    };
    std::printf("| quantity | paper |");
    for (uint64_t s : seeds) std::printf(" seed %llu |", static_cast<unsigned long long>(s));
    std::printf("\n|---|---|");
    for (std::size_t i = 0; i < seeds.size(); ++i) std::printf("---|");
    std::printf("\n");
    using R = calib::Result;
    row("bias, g", "-5.0137e-4", [&](const R& r) { return num("%.5e", r.bias); });
    row("base error, g", "3.8549e-4", [&](const R& r) { return num("%.5e", r.base_error); });
    row("B GOST 100 s, g", "4e-6", [&](const R& r) { return num("%.3e", r.b_gost_100); });
    row("B GOST 200 s, g", "2.5e-6", [&](const R& r) { return num("%.3e", r.b_gost_200); });
    row("B Allan, g (tau_cp s)", "2.1e-6 (200)", [&](const R& r) {
      return num("%.3e", val(r.nt_x.B)) + num(" (%.0f)", r.nt_x.tau_cp_s.value_or(0));
    });
    row("Q, g*h", "6.3603e-10", [&](const R& r) { return num("%.4e", A::q_per_hour(val(r.nt_x.Q))); });
    row("N, g*h^0.5", "2.2306e-7", [&](const R& r) { return num("%.4e", A::n_per_hour(val(r.nt_x.N))); });
    row("K, g/h^0.5", "5.1167e-6", [&](const R& r) { return num("%.4e", A::k_per_hour(val(r.nt_x.K))); });
    row("R", "not determinable", [&](const R& r) { return r.nt_x.R.value ? std::string("value") : r.nt_x.R.reason; });
    row("B Allan filtered, g (tau_cp s)", "0.86e-6", [&](const R& r) {
      return num("%.3e", val(r.nt_y.B)) + num(" (%.0f)", r.nt_y.tau_cp_s.value_or(0));
    });
    row("ratio unfiltered/filtered", "2.5", [&](const R& r) { return num("%.2f", val(r.nt_x.B) / val(r.nt_y.B)); });
    row("RMS x, y (g)", "0.04-0.06, 0.03-0.045",
        [&](const R& r) { return num("%.3e", r.rms_x) + num(", %.3e", r.rms_y); });
    std::printf("| settling time (5 %%), s | 0.003 | %.4f |\n", lf.settling_time_s);
    std::printf("| bandwidth 0.5 with filter, Hz | 492 | %.1f |\n", lf.bandwidth_0p5_hz);
    for (std::size_t i = 0; i < rs.size(); ++i) {
      const R& r = rs[i];
      std::printf("\nseed %llu (taus %s):\n", static_cast<unsigned long long>(seeds[i]), spec.taus.c_str());
      for (const auto* nt : {&r.nt_x, &r.nt_y}) {
        std::printf(" %s segments:", nt == &r.nt_x ? "x" : "y");
        for (const auto& s : nt->paper.segments)
          std::printf(" [%.3g..%.3g slope %.2f %s]", s.tau_lo_s, s.tau_hi_s, s.slope, s.term.c_str());
        std::printf("\n  wls (chi2/dof %.3g, model error %.3g): Q %s\n   N %s\n   B %s\n   K %s\n   R %s\n", nt->wls.chi2_per_dof, nt->wls.model_error,
                    term(nt->wls.Q, 1 / 3600.0).c_str(), term(nt->wls.N, 1 / 60.0).c_str(),
                    term(nt->wls.B, 1).c_str(), term(nt->wls.K, 60).c_str(), term(nt->wls.R, 3600).c_str());
        std::printf("   share/z:");
        for (int k = 0; k < 5; ++k) std::printf(" %c %.2f/%.1f", "QNBKR"[k], nt->wls.share[static_cast<std::size_t>(k)], nt->wls.z[static_cast<std::size_t>(k)]);
        std::printf("\n");
      }
      if (curves) {
        std::printf("  tau          x            y\n");
        for (std::size_t j = 0; j < r.adev_x.size() && j < r.adev_y.size(); ++j)
          std::printf("  %10.3f  %.4e  %.4e\n", r.adev_x[j].tau_s, r.adev_x[j].dev, r.adev_y[j].dev);
      }
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dut_calibrate: %s\n", e.what());
    return 2;
  }
}
