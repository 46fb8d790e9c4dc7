// Prints the calibration table of an emulated DUT profile: the paper's procedure
// run on the model and evaluated by the rig's own analysis (docs/plant.md).
//   dut_calibrate [overrides.toml] [--seed N]
#include <cstdio>
#include <cstring>
#include <string>

#include "plant/dut/loop_figures.hpp"
#include "procedures/analysis/noise_terms.hpp"
#include "rig/core/toml_util.hpp"
#include "tests/plant/paper_procedure.hpp"

using namespace rig::plant;

namespace {
double val(const rig::analysis::Term& t) { return t.value ? *t.value : std::nan(""); }
}  // namespace

int main(int argc, char** argv) {
  try {
    toml::table over;
    uint64_t seed = 1;
    for (int i = 1; i < argc; ++i) {
      if (!std::strcmp(argv[i], "--seed") && i + 1 < argc) seed = std::stoull(argv[++i]);
      else over = rig::cfg::parse_file(argv[i]);
    }
    const DutParams p = load_dut_params(&over);
    EmulatedDut dut(p, seed);
    const calib::Result r = calib::run(dut, calib::Spec{});
    const LoopFigures lf = loop_figures(&over, p.filter);
    namespace A = rig::analysis;
    const double bx = val(r.nt_x.B), by = val(r.nt_y.B);
    std::printf("| quantity | paper | emulated (seed %llu) |\n|---|---|---|\n", static_cast<unsigned long long>(seed));
    std::printf("| bias, g | -5.0137e-4 | %.5e |\n", r.bias);
    std::printf("| base error, g | 3.8549e-4 | %.5e |\n", r.base_error);
    std::printf("| B GOST 100 s, g | 4e-6 | %.3e |\n", r.b_gost_100);
    std::printf("| B GOST 200 s, g | 2.5e-6 | %.3e |\n", r.b_gost_200);
    std::printf("| B Allan, g (tau_cp s) | 2.1e-6 (200) | %.3e (%.0f) |\n", bx, r.nt_x.tau_cp_s.value_or(0));
    std::printf("| Q, g*h | 6.3603e-10 | %.4e |\n", A::q_per_hour(val(r.nt_x.Q)));
    std::printf("| N, g*h^0.5 | 2.2306e-7 | %.4e |\n", A::n_per_hour(val(r.nt_x.N)));
    std::printf("| K, g/h^0.5 | 5.1167e-6 | %.4e |\n", A::k_per_hour(val(r.nt_x.K)));
    std::printf("| R | not determinable | %s |\n", r.nt_x.R.value ? "value" : r.nt_x.R.reason.c_str());
    std::printf("| B Allan filtered, g (tau_cp s) | 0.86e-6 | %.3e (%.0f) |\n", by, r.nt_y.tau_cp_s.value_or(0));
    std::printf("| ratio unfiltered/filtered | 2.5 | %.2f |\n", bx / by);
    const double mx = calib::b_from_minimum(r.adev_x), my = calib::b_from_minimum(r.adev_y);
    std::printf("| B from sigma_min/0.664 (tau >= 10 s): x, y, ratio | 2.1e-6, 0.86e-6, 2.5 | %.3e, %.3e, %.2f |\n", mx, my, mx / my);
    std::printf("| RMS x, y (g) | 0.04-0.06, 0.03-0.045 | %.3e, %.3e |\n", r.rms_x, r.rms_y);
    std::printf("| settling time (5 %%), s | 0.003 | %.4f |\n", lf.settling_time_s);
    std::printf("| bandwidth 0.5 with filter, Hz | 492 | %.1f |\n", lf.bandwidth_0p5_hz);
    std::printf("\nx Allan:\n");
    for (const auto& d : r.adev_x) std::printf("  tau %10.3f  x %.4e\n", d.tau_s, d.dev);
    std::printf("y Allan:\n");
    for (const auto& d : r.adev_y) std::printf("  tau %10.3f  y %.4e\n", d.tau_s, d.dev);
    std::printf("x segments:");
    for (const auto& s : r.nt_x.paper.segments) std::printf(" [%.3g..%.3g slope %.2f %s]", s.tau_lo_s, s.tau_hi_s, s.slope, s.term.c_str());
    std::printf("\ny segments:");
    for (const auto& s : r.nt_y.paper.segments) std::printf(" [%.3g..%.3g slope %.2f %s]", s.tau_lo_s, s.tau_hi_s, s.slope, s.term.c_str());
    std::printf("\nwls x: Q %s N %s B %s K %s\n", r.nt_x.wls.Q.reason.c_str(), r.nt_x.wls.N.reason.c_str(), r.nt_x.wls.B.reason.c_str(), r.nt_x.wls.K.reason.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dut_calibrate: %s\n", e.what());
    return 2;
  }
}
