// A realistic run folder for the report and history tests, generated here so the tests do
// not depend on `rig run`: passport.json in the docs/contracts.md shape, and analysis.json
// with curves shaped like the paper's (Allan curve from the docs/method.md noise figures,
// a PSD with 72 Hz and 970 Hz peaks, a 2nd-order loop step and amplitude response).
#pragma once
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <vector>
#include <string>

#include <nlohmann/json.hpp>

#include "analysis/envelope.hpp"
#include "analysis/json.hpp"
#include "analysis/noise_terms.hpp"

namespace rig::test {

using nlohmann::json;

inline json fixture_passport(const std::string& serial = "QA-0042", const std::string& outcome = "PASS",
                             const std::string& started = "2026-11-20T08:00:00Z") {
  auto v = [](double value, const char* unit, json limits, const char* outcome_, const char* reason = "") {
    return json{{"value", value}, {"unit", unit}, {"lo", nullptr}, {"hi", nullptr},
                {"limits", limits}, {"outcome", outcome_}, {"reason", reason}};
  };
  json values = {
      {"bias", v(-5.0137e-4, "g", {-1e-3, 1e-3}, "PASS")},
      {"base_error", v(3.8549e-4, "g", {-1e-3, 1e-3}, "PASS")},
      {"in_run_b_gost_100s", v(4.0e-6, "g", {nullptr, 1e-5}, "PASS")},
      {"in_run_b_gost_200s", v(2.5e-6, "g", {nullptr, 1e-5}, "PASS")},
      {"in_run_b_allan", v(2.1e-6, "g", {nullptr, 5e-6}, "PASS")},
      {"tau_cp", v(200, "s", nullptr, "UNSET")},
      {"q", v(6.3603e-10, "g*h", nullptr, "UNSET")},
      {"n", v(2.2306e-7, "g*h^0.5", nullptr, "UNSET")},
      {"k", v(5.1167e-6, "g/h^0.5", nullptr, "UNSET")},
      {"r", json{{"value", nullptr}, {"unit", "g/h"}, {"lo", nullptr}, {"hi", nullptr}, {"limits", nullptr},
                 {"outcome", "UNSET"}, {"reason", "needs a record longer than 50 h"}}},
      {"in_run_b_allan_filtered", v(0.86e-6, "g", {nullptr, 5e-6}, "PASS")},
      {"rms_unfiltered", v(0.0585, "g", nullptr, "UNSET")},
      {"rms_filtered", v(0.0448, "g", {nullptr, 0.05}, "PASS")},
      {"bandwidth_0p5", v(492, "Hz", {450, 550}, "PASS")},
      {"settling_time", v(0.003, "s", {nullptr, 0.01}, "PASS")},
      {"accuracy_class", v(2, "-", nullptr, "UNSET", "precision")},
  };
  values["in_run_b_allan"]["lo"] = 1.8e-6;
  values["in_run_b_allan"]["hi"] = 2.5e-6;
  return json{{"schema", "rig.passport/1"},
              {"serial", serial},
              {"profile", "paper"},
              {"plant", "emulated"},
              {"software", "rig 0.1.0"},
              {"started", started},
              {"finished", "2026-11-20T09:52:31Z"},
              {"outcome", outcome},
              {"out_dir", "runs/" + serial},
              {"captures", {"captures/run01-U10.cap", "captures/run02-U20.cap", "captures/in-run-U10.cap"}},
              {"phases",
               {{{"id", "mount"}, {"title", "Mount and home"}, {"status", "done"}, {"started", started},
                 {"finished", started}, {"message", ""}},
                {{"id", "u10u20"}, {"title", "12 × 100 s at U10/U20"}, {"status", "done"}, {"started", started},
                 {"finished", started}, {"message", "12 runs"}}}},
              {"aborted_reason", nullptr},
              {"values", values}};
}

// σ(τ) of the docs/method.md noise figures (seconds basis): Q, N, B, K.
inline double model_adev(double tau) {
  const double Q = 6.3603e-10 * 3600, N = 2.2306e-7 * 60, B = 2.1e-6 / 0.664 * 0.664, K = 5.1167e-6 / 60;
  return std::sqrt(3 * Q * Q / (tau * tau) + N * N / tau + 0.441 * B * B / 0.441 * 0.441 + K * K * tau / 3);
}

// One channel's allan.* object, in the analysis library's own JSON view: the docs/method.md figures
// set as the terms (Q, N, B, K; R not identified), the curves computed by the library.
inline json fixture_allan(double scale) {
  namespace an = rig::analysis;
  std::vector<an::DevPoint> pts;
  for (double tau = 0.001; tau < 1800; tau *= 2) {
    an::DevPoint p;
    p.tau_s = tau;
    p.m = static_cast<std::size_t>(std::lround(tau * 1000));
    p.dev = model_adev(tau) * scale;
    p.n_terms = static_cast<std::size_t>(3.6e6 / (tau * 1000));
    const double rel = 1 / std::sqrt(std::max(3.6e6 / (tau * 1000), 2.0));
    p.lo = p.dev * (1 - rel);
    p.hi = p.dev * (1 + rel);
    p.edf = 3.6e6 / (tau * 1000);
    pts.push_back(p);
  }
  auto term = [](double v, const char* unit, double rel) {
    an::Term t;
    t.value = v;
    t.lo = v * (1 - rel);
    t.hi = v * (1 + rel);
    t.unit = unit;
    t.reason = "weighted least squares";
    return t;
  };
  an::NoiseTerms nt;
  nt.Q = term(6.3603e-10 * 3600 * scale, "g*s", 0.2);
  nt.N = term(2.2306e-7 * 60 * scale, "g*s^0.5", 0.1);
  nt.B = term(2.1e-6 * scale, "g", 0.15);
  nt.K = term(5.1167e-6 / 60 * scale, "g/s^0.5", 0.3);
  nt.R.unit = "g/s";
  nt.R.reason = "needs a longer record";
  nt.tau_cp_s = 200.0;
  nt.sigma_cp = model_adev(200) * scale;
  nt.paper.ok = true;
  nt.paper.coef = {std::log10(model_adev(1) * scale), -0.5, 0.02, 0.004, 0.0};
  nt.paper.segments = {{0.001, 0.05, -0.9, 0.007, model_adev(0.007) * scale, "Q", 0},
                       {50, 800, 0.0, 200, model_adev(200) * scale, "B", 0}};
  nt.wls.ok = true;
  nt.wls.Q = nt.Q;
  nt.wls.N = nt.N;
  nt.wls.B = nt.B;
  nt.wls.K = nt.K;
  std::vector<double> taus;
  for (const auto& p : pts) taus.push_back(p.tau_s);
  nt.curves = an::fitted_curves(nt, taus);
  return {{"oadev", an::dev_to_json(pts)}, {"noise_terms", an::noise_terms_to_json(nt)}};
}

inline json fixture_psd(double gain_hf) {
  json f = json::array(), p = json::array();
  for (double hz = 0.5; hz <= 500; hz += 0.5) {
    double s = 1e-9 * (1 + 0.5 / hz);
    s += 4e-6 * std::exp(-std::pow((hz - 72) / 1.5, 2));
    s += 2e-6 * gain_hf * std::exp(-std::pow((hz - 470) / 2, 2));
    f.push_back(hz);
    p.push_back(s);
  }
  return {{"f_hz", f}, {"psd", p}, {"unit", "g^2/Hz"},
          {"peaks", {{{"f_hz", 72.0}, {"psd", 4e-6}, {"prominence_db", 36.0}},
                     {{"f_hz", 470.0}, {"psd", 2e-6 * gain_hf}, {"prominence_db", 30.0}}}}};
}

inline json fixture_analysis() {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0, 0.04);
  json runs = json::array();
  for (int i = 1; i <= 12; ++i) {
    const bool u10 = i % 2 == 1;
    runs.push_back({{"index", i}, {"orientation", u10 ? "U10" : "U20"},
                    {"mean_g", -5.0137e-4 + (u10 ? 1 : -1) * 3.8549e-4 + 1e-6 * std::sin(i)},
                    {"n", 100000}, {"capture", "captures/run" + std::to_string(i) + ".cap"}});
  }
  json m100 = json::array(), m200 = json::array();
  for (int i = 0; i < 18; ++i) m100.push_back(-1.16e-4 + 4e-6 * std::sin(i * 0.9));
  for (int i = 0; i < 9; ++i) m200.push_back(-1.16e-4 + 2.5e-6 * std::sin(i * 1.7));
  // 60 s of a quantised output (steps of 2.9e-6 g) with a slow wander, and its filtered copy.
  std::vector<double> x, y;
  double yf = 0, yf1 = 0;
  for (int i = 0; i < 60000; ++i) {
    const double t = i / 1000.0;
    const double v = 2.9e-6 * std::round((3e-6 * std::sin(t / 9) + 0.05 * std::sin(2 * M_PI * 72 * t) + noise(rng)) / 2.9e-6);
    const double out = 0.148895 * v + 1.228261 * yf - 0.377156 * yf1;  // W_ф(z) (docs/method.md)
    yf1 = yf;
    yf = out;
    x.push_back(v);
    y.push_back(out);
  }
  const json envelope = rig::analysis::envelope_to_json(rig::analysis::block_envelope(x, 1000, 1000),
                                                        rig::analysis::block_envelope(y, 1000, 1000),
                                                        "raw capture, drift: bias and base error removed");
  x.resize(2000);
  y.resize(2000);
  json ts = json::array(), sx = json::array(), sy = json::array();
  for (int i = 0; i <= 200; ++i) {
    const double t = i * 5e-5, wn = 2 * M_PI * 700, z = 0.7;
    const double wd = wn * std::sqrt(1 - z * z);
    const double s = 1 - std::exp(-z * wn * t) * (std::cos(wd * t) + z / std::sqrt(1 - z * z) * std::sin(wd * t));
    ts.push_back(t);
    sx.push_back(s);
    sy.push_back(s * (1 - std::exp(-t / 4e-4)));
  }
  json fh = json::array(), mx = json::array(), my = json::array();
  for (double f = 1; f <= 5000; f *= 1.1) {
    const double r = f / 700;
    const double h = 1 / std::sqrt(std::pow(1 - r * r, 2) + std::pow(1.4 * r, 2));
    fh.push_back(f);
    mx.push_back(h);
    my.push_back(h / std::sqrt(1 + std::pow(f / 900, 2)));
  }
  return {{"schema", "rig.analysis/1"},
          {"runs", runs},
          {"in_run", {{"capture", "captures/in-run-U10.cap"}, {"n", 1800000},
                      {"blocks", {{{"block_s", 100}, {"means_g", m100}, {"b_g", 4e-6}},
                                  {{"block_s", 200}, {"means_g", m200}, {"b_g", 2.5e-6}}}}}},
          {"allan", {{"x", fixture_allan(1.0)}, {"y", fixture_allan(0.41)}, {"confidence", 0.6826894921370859}}},
          {"output_envelope", envelope},
          {"dut", {{"serial", "QA-0042"}, {"firmware", "1.4.0"}, {"temperature_c", 22.5}}},
          {"device_time_s", 6839.0},
          {"psd", {{"x", fixture_psd(1.0)}, {"y", fixture_psd(0.4)}}},
          {"timeseries", {{"rate_hz", 1000}, {"t0_s", 0}, {"x", x}, {"y", y}, {"note", "first 2 s of the raw capture"}}},
          {"loop", {{"step", {{"t_s", ts}, {"x", sx}, {"y", sy}}},
                    {"freq", {{"f_hz", fh}, {"mag_x", mx}, {"mag_y", my}}},
                    {"bandwidth_0p5_hz", 492},
                    {"settling_time_s", 0.003},
                    {"settling_band", 0.05},
                    {"dc_gain", 1.0}}}};
}

// A temporary folder removed at scope exit.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "rig-report-XXXXXX").string();
    if (!mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
    path = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
};

// A whole file as a string ("" when it cannot be read).
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void write_file(const std::filesystem::path& p, const std::string& text) {
  std::filesystem::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

// A complete run folder: passport.json + analysis.json.
inline void write_run(const std::filesystem::path& dir, const json& passport, const json* analysis) {
  write_file(dir / "passport.json", passport.dump(2));
  if (analysis) write_file(dir / "analysis.json", analysis->dump());
}

}  // namespace rig::test
