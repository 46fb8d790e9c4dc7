// Prints the calibration table of an emulated DUT profile: the shipped acceptance procedure
// (`rig run --plant emulated`, paper profile) on the model, read off its passport and
// analysis.json (docs/plant.md).
//   dut_calibrate [overrides.toml] [--seed N]... [--taus GRID] [--curves] [--rig PATH] [--save DIR]
// overrides.toml holds [plant.dut] keys. Several --seed give one column per seed (each a
// full 110 min procedure, about 3 s of CPU); --rig names the rig binary (default: the one
// built with this tool); --save keeps each seed's passport and analysis.json as
// DIR/seed-N.passport.json, DIR/seed-N.analysis.json (a sweep is counted from these without
// running it again; the captures themselves are not kept).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "rig/core/toml_util.hpp"
#include "tests/plant/paper_run.hpp"

using rig::plant::calib::PaperRun;
using json = nlohmann::json;

namespace {

double num_or_nan(const json& v) { return v.is_number() ? v.get<double>() : std::nan(""); }
double val(const PaperRun& r, const char* name) { return num_or_nan(r.passport["values"][name]["value"]); }

std::string num(const char* fmt, double v) {
  char b[64];
  std::snprintf(b, sizeof b, fmt, v);
  return b;
}

// "v [lo, hi]" of a weighted-fit term (analysis.json lsq_fit.terms) scaled to passport units, or its reason.
std::string term(const json& t, double scale) {
  if (!t.contains("value") || t["value"].is_null()) return "null (" + t.value("reason", std::string()) + ")";
  char b[128];
  std::snprintf(b, sizeof b, "%.3e [%.3e, %.3e]", num_or_nan(t["value"]) * scale, num_or_nan(t["lo"]) * scale,
                num_or_nan(t["hi"]) * scale);
  return b;
}

// Each run's two files, as `rig` wrote them (re-serialised), for counting a sweep afterwards.
void save_runs(const std::string& dir, const std::vector<PaperRun>& rs) {
  std::filesystem::create_directories(dir);
  for (const PaperRun& r : rs) {
    const std::string stem = dir + "/seed-" + std::to_string(r.seed);
    for (const auto& [suffix, doc] : {std::pair{".passport.json", &r.passport}, std::pair{".analysis.json", &r.analysis}}) {
      std::ofstream out(stem + suffix);
      out << doc->dump() << "\n";
      if (!out) throw std::runtime_error("cannot write " + stem + suffix);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    toml::table over;
    bool have_over = false, curves = false;
    std::vector<uint64_t> seeds;
    rig::plant::calib::RunSpec spec;
    std::string rig_binary = RIG_BINARY;
    std::string save_dir;
    for (int i = 1; i < argc; ++i) {
      if (!std::strcmp(argv[i], "--seed") && i + 1 < argc) seeds.push_back(std::stoull(argv[++i]));
      else if (!std::strcmp(argv[i], "--taus") && i + 1 < argc) spec.taus = argv[++i];
      else if (!std::strcmp(argv[i], "--rig") && i + 1 < argc) rig_binary = argv[++i];
      else if (!std::strcmp(argv[i], "--save") && i + 1 < argc) save_dir = argv[++i];
      else if (!std::strcmp(argv[i], "--curves")) curves = true;
      else {
        over = rig::cfg::parse_file(argv[i]);
        have_over = true;
      }
    }
    if (seeds.empty()) seeds.push_back(1);
    if (have_over) spec.dut = &over;
    const std::vector<PaperRun> rs = rig::plant::calib::run_seeds(rig_binary, spec, seeds, 2);
    if (!save_dir.empty()) save_runs(save_dir, rs);
    auto row = [&](const char* name, const char* paper, auto f) {
      std::printf("| %s | %s |", name, paper);
      for (const auto& r : rs) std::printf(" %s |", f(r).c_str());
      std::printf("\n");
    };
    std::printf("| quantity | paper |");
    for (uint64_t s : seeds) std::printf(" seed %llu |", static_cast<unsigned long long>(s));
    std::printf("\n|---|---|");
    for (std::size_t i = 0; i < seeds.size(); ++i) std::printf("---|");
    std::printf("\n");
    using R = PaperRun;
    auto allan = [](const R& r, const char* ch) -> const json& { return r.analysis["allan"][ch]["noise_terms"]; };
    row("bias, g", "-5.0137e-4", [&](const R& r) { return num("%.5e", val(r, "bias")); });
    row("base error, g", "3.8549e-4", [&](const R& r) { return num("%.5e", val(r, "base_error")); });
    row("B GOST 100 s, g", "4e-6", [&](const R& r) { return num("%.3e", val(r, "in_run_b_gost_100s")); });
    row("B GOST 200 s, g", "2.5e-6", [&](const R& r) { return num("%.3e", val(r, "in_run_b_gost_200s")); });
    row("B Allan, g (tau_cp s)", "2.1e-6 (200)", [&](const R& r) {
      return num("%.3e", val(r, "in_run_b_allan")) + num(" (%.0f)", val(r, "tau_cp"));
    });
    row("Q, g*h", "6.3603e-10", [&](const R& r) { return num("%.4e", val(r, "q")); });
    row("N, g*h^0.5", "2.2306e-7", [&](const R& r) { return num("%.4e", val(r, "n")); });
    row("K, g/h^0.5", "5.1167e-6", [&](const R& r) { return num("%.4e", val(r, "k")); });
    row("R", "not determinable", [&](const R& r) {
      return std::isnan(val(r, "r")) ? r.passport["values"]["r"].value("reason", std::string("null")) : "value";
    });
    row("B Allan filtered, g (tau_cp s)", "0.86e-6", [&](const R& r) {
      return num("%.3e", val(r, "in_run_b_allan_filtered")) + num(" (%.0f)", num_or_nan(allan(r, "y")["tau_cp_s"]));
    });
    row("ratio unfiltered/filtered", "2.5",
        [&](const R& r) { return num("%.2f", val(r, "in_run_b_allan") / val(r, "in_run_b_allan_filtered")); });
    row("RMS x, y (g)", "0.04-0.06, 0.03-0.045",
        [&](const R& r) { return num("%.3e", val(r, "rms_unfiltered")) + num(", %.3e", val(r, "rms_filtered")); });
    row("settling time, s", "0.003", [&](const R& r) { return num("%.4f", val(r, "settling_time")); });
    row("bandwidth 0.5 with filter, Hz", "492", [&](const R& r) { return num("%.1f", val(r, "bandwidth_0p5")); });
    for (const R& r : rs) {
      std::printf("\nseed %llu:\n", static_cast<unsigned long long>(r.seed));
      for (const char* ch : {"x", "y"}) {
        const json& nt = allan(r, ch);
        std::printf(" %s segments:", ch);
        for (const auto& s : nt["paper_fit"]["segments"])
          std::printf(" [%.3g..%.3g slope %.2f %s]", num_or_nan(s["tau_from_s"]), num_or_nan(s["tau_to_s"]),
                      num_or_nan(s["slope"]), s.value("term", std::string()).c_str());
        const json& w = nt["lsq_fit"];
        const json& t = w["terms"];
        std::printf("\n  wls (chi2/dof %.3g, model error %.3g): Q %s\n   N %s\n   B %s\n   K %s\n   R %s\n",
                    num_or_nan(w["chi2_per_dof"]), num_or_nan(w["model_error"]), term(t["Q"], 1 / 3600.0).c_str(),
                    term(t["N"], 1 / 60.0).c_str(), term(t["B"], 1).c_str(), term(t["K"], 60).c_str(),
                    term(t["R"], 3600).c_str());
        std::printf("   share/z:");
        for (const char* k : {"Q", "N", "B", "K", "R"})
          std::printf(" %s %.2f/%.1f", k, num_or_nan(t[k]["share"]), num_or_nan(t[k]["z"]));
        std::printf("\n");
      }
      if (curves) {
        const json& ax = r.analysis["allan"]["x"]["oadev"];
        const json& ay = r.analysis["allan"]["y"]["oadev"];
        std::printf("  tau          x            y\n");
        for (std::size_t j = 0; j < ax.size() && j < ay.size(); ++j)
          std::printf("  %10.3f  %.4e  %.4e\n", num_or_nan(ax[j]["tau_s"]), num_or_nan(ax[j]["dev"]),
                      num_or_nan(ay[j]["dev"]));
      }
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dut_calibrate: %s\n", e.what());
    return 2;
  }
}
