#include "procedures/acceptance/procedure.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "plant/dut/loop_figures.hpp"
#include "analysis/json.hpp"
#include "procedures/acceptance/analysis_doc.hpp"
#include "procedures/acceptance/record.hpp"
#include "analysis/allan.hpp"
#include "analysis/rms.hpp"
#include "analysis/gost.hpp"
#include "analysis/noise_terms.hpp"
#include "analysis/psd.hpp"
#include "rig/capture/capture.hpp"
#include "rig/core/errors.hpp"

namespace rig::acceptance {

namespace {

std::optional<std::pair<double, double>> limit(const Profile& p, const std::string& name) {
  auto it = p.limits.find(name);
  if (it == p.limits.end()) return std::nullopt;
  return it->second;
}

std::string run_id(std::size_t i, Orientation o) { return fmt::format("run{:02d}-{}", i + 1, to_string(o)); }

capture::Loaded load_capture(PhaseContext& ctx, const std::string& rel) {
  capture::Loaded l = capture::load(ctx.out_dir + "/" + rel);
  if (!l.recovery.complete) ctx.log->warn("{}", l.recovery.summary(rel));
  if (l.samples.empty()) throw HardwareError(rel + ": capture holds no samples");
  return l;
}

// The drift g_dr(t) = x(t) - g_sist -+ g_dA (docs/method.md, after (4)) of a capture at orientation o.
std::vector<double> drift(const std::vector<double>& x, const nlohmann::json& state, Orientation o) {
  std::vector<double> d(x);
  if (!state.contains("bias")) return d;  // bias phase not run: the offset does not change Allan/B/PSD
  const double bias = state["bias"]["bias"].get<double>();
  const double base = state["bias"]["base_error"].get<double>();
  const int s10 = state["bias"]["sign_u10"].get<int>();
  const double off = bias + (o == Orientation::U10 ? s10 : -s10) * base;
  for (double& v : d) v -= off;
  return d;
}

void phase_run(PhaseContext& ctx, const Profile& p, std::size_t i) {
  const Orientation o = p.order[i];
  const Recorded r = position_and_record(ctx, p, o, p.run_s, run_id(i, o));
  nlohmann::json& runs = ctx.state["runs"];
  runs[std::to_string(i + 1)] = {{"index", i + 1},          {"orientation", to_string(o)}, {"mean_g", r.mean_x},
                                 {"mean_y_g", r.mean_y},     {"n", r.samples},             {"capture", r.capture},
                                 {"lost", r.lost},           {"gaps", r.gaps},             {"attempts", r.attempts}};
}

void phase_bias(PhaseContext& ctx, const Profile& p) {
  std::vector<double> x10, x20;
  for (std::size_t i = 0; i < p.order.size(); ++i) {
    const auto& run = ctx.state["runs"].at(std::to_string(i + 1));
    (p.order[i] == Orientation::U10 ? x10 : x20).push_back(run["mean_g"].get<double>());
  }
  const BiasBaseError b = bias_and_base_error(x10, x20);
  ctx.state["bias"] = {{"bias", b.bias}, {"base_error", b.base_error}, {"sign_u10", b.sign_u10}};
  ctx.values.set("bias", b.bias, "formula (3), GOST R 8.736 95 % interval", b.bias - b.bias_ci_half,
                 b.bias + b.bias_ci_half);
  ctx.values.set("base_error", b.base_error,
                 fmt::format("formula (4); enters x10 with {}", b.sign_u10 > 0 ? "+" : "-"),
                 b.base_error - b.base_ci_half, b.base_error + b.base_ci_half);
}

void phase_in_run_b(PhaseContext& ctx, const Profile& p) {
  const std::string rel = ctx.state["in_run"]["capture"].get<std::string>();
  const capture::Loaded l = load_capture(ctx, rel);
  const std::vector<double> x = capture::channel_x(l.samples);
  nlohmann::json blocks = nlohmann::json::array();
  for (std::size_t k = 0; k < p.in_run_blocks_s.size(); ++k) {
    const double bs = p.in_run_blocks_s[k];
    const auto len = static_cast<std::size_t>(bs * p.rate_hz + 0.5);
    const analysis::InRunB b = analysis::in_run_b(x, len);
    blocks.push_back({{"block_s", bs}, {"means_g", analysis::block_means(x, len)}, {"b_g", b.value}});
    const std::string name = k == 0   ? "in_run_b_gost_100s"
                             : k == 1 ? "in_run_b_gost_200s"
                                      : fmt::format("in_run_b_gost_{}s", bs);
    ctx.values.set(name, b.value, fmt::format("(max-min)/2 of {} block means of {} s", b.blocks, bs));
  }
  ctx.state["in_run"]["blocks"] = blocks;
  const Measurement* b100 = ctx.values.find("in_run_b_gost_100s");
  if (b100 && b100->value) {
    if (auto c = accuracy_class(p.classes, *b100->value)) {
      ctx.values.set("accuracy_class", static_cast<double>(*c), p.classes[*c - 1].name);
    } else {
      Measurement& m = ctx.values.set("accuracy_class", std::nullopt,
                                      fmt::format("B = {:.3g} g exceeds every class in the profile", *b100->value));
      m.outcome = Outcome::Fail;
    }
    Measurement* m = ctx.values.find("accuracy_class");
    if (m->value && m->outcome == Outcome::Unset) m->outcome = Outcome::Pass;  // a class was found
  }
}

// Allan family + noise terms of one channel; writes the passport values.
nlohmann::json allan_channel(PhaseContext& ctx, const Profile& p, const std::vector<double>& d, bool filtered) {
  analysis::DevOptions opt;
  opt.type = analysis::Deviation::OADEV;
  opt.data = analysis::DataKind::Frequency;
  opt.rate_hz = p.rate_hz;
  opt.taus = analysis::parse_tau_grid(p.taus);
  opt.confidence = p.confidence;
  const std::vector<analysis::DevPoint> dev = analysis::deviation(d, opt);
  const double T = static_cast<double>(d.size()) / p.rate_hz;
  // One model fit (R a candidate on every record; its reason notes a record shorter than the
  // profile's [analysis] r_min_record_s): the passport and analysis.json carry the same fit.
  const analysis::NoiseTerms nt = analysis::noise_terms(dev, T, p.r_min_record_s);
  auto term_value = [&](const char* name, const analysis::Term& t, double scale, const std::string& why) {
    if (t.value) {
      ctx.values.set(name, *t.value * scale, why.empty() ? t.reason : why,
                     t.lo ? std::optional<double>(*t.lo * scale) : std::nullopt,
                     t.hi ? std::optional<double>(*t.hi * scale) : std::nullopt);
    } else {
      ctx.values.set(name, std::nullopt, t.reason.empty() ? "not identifiable from this record" : t.reason);
    }
  };
  if (!filtered) {
    // B as the profile's [analysis] b_allan says: "paper" (sigma(tau_cp)/0.664; its reason names
    // flat segment, polynomial minimum or least-squares fallback) or "lsq" (the model's B).
    term_value("in_run_b_allan", p.b_allan == "lsq" ? nt.wls.B : nt.B, 1.0, "");
    if (nt.tau_cp_s && nt.b_method == "flat_segment")
      ctx.values.set("tau_cp", *nt.tau_cp_s, nt.B.reason);
    else if (nt.tau_cp_s)
      ctx.values.set("tau_cp", *nt.tau_cp_s, "minimum of the paper's polynomial (no flat segment)");
    else ctx.values.set("tau_cp", std::nullopt, nt.B.reason.empty() ? "no flat segment" : nt.B.reason);
    // IEEE 952 terms quoted per hour (docs/method.md): Q g*s -> g*h, N g*s^0.5 -> g*h^0.5, K g/s^0.5 -> g/h^0.5, R g/s -> g/h.
    term_value("q", nt.Q, 1.0 / 3600.0, "");
    term_value("n", nt.N, 1.0 / 60.0, "");
    term_value("k", nt.K, 60.0, "");
    term_value("r", nt.R, 3600.0, "");
  } else {
    term_value("in_run_b_allan_filtered", nt.B, 1.0, "on the filtered output y(t)");
  }
  return {{"oadev", analysis::dev_to_json(dev)}, {"noise_terms", analysis::noise_terms_to_json(nt)}};
}

void phase_raw_analysis(PhaseContext& ctx, const Profile& p) {
  const std::string rel = ctx.state["raw"]["capture"].get<std::string>();
  const capture::Loaded l = load_capture(ctx, rel);
  const std::vector<double> x = drift(capture::channel_x(l.samples), ctx.state, p.raw_orientation);
  const std::vector<double> y = drift(capture::channel_y(l.samples), ctx.state, p.raw_orientation);
  nlohmann::json a;
  a["allan"]["x"] = allan_channel(ctx, p, x, false);
  ctx.report(0.45);
  a["allan"]["y"] = allan_channel(ctx, p, y, true);
  ctx.report(0.9);
  // RMS error of the output (criterion 1), of the drift (bias and base error removed).
  ctx.values.set("rms_unfiltered", analysis::rms(x), "RMS of x(t) drift over the raw capture");
  ctx.values.set("rms_filtered", analysis::rms(y), "RMS of y(t) drift over the raw capture");
  for (const auto& [ch, v] : {std::pair{"x", &x}, std::pair{"y", &y}}) {
    const analysis::Psd psd = analysis::welch(*v, p.rate_hz);
    a["psd"][ch] = analysis::psd_to_json(psd, analysis::find_peaks(psd));
  }
  const std::size_t n_ts = std::min<std::size_t>(x.size(), static_cast<std::size_t>(2 * p.rate_hz));
  a["timeseries"] = {{"rate_hz", p.rate_hz},
                     {"t0_s", 0.0},
                     {"x", std::vector<double>(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(n_ts))},
                     {"y", std::vector<double>(y.begin(), y.begin() + static_cast<std::ptrdiff_t>(n_ts))},
                     {"note", "first 2 s of the raw capture (drift: bias and base error removed)"}};
  ctx.state["analysis"] = a;
}

void phase_loop(PhaseContext& ctx, const Profile& p) {
  const toml::table* dut_cfg = p.plant.get_as<toml::table>("dut");
  const design::LoopFigures f = plant::loop_figures(dut_cfg, p.filter);
  ctx.values.set("bandwidth_0p5", f.bandwidth_0p5_hz, "closed loop with the output filter, 0.5 level (model)");
  ctx.values.set("settling_time", f.settling_time_s,
                 fmt::format("closed loop, 1 g step, {:g} % band (model)", f.settling_band * 100));
  ctx.state["loop"] = loop_to_json(f);
}

}  // namespace

BiasBaseError bias_and_base_error(const std::vector<double>& x10, const std::vector<double>& x20) {
  if (x10.empty() || x10.size() != x20.size())
    throw std::invalid_argument("formulas (3), (4) need equal, non-zero numbers of U10 and U20 runs");
  std::vector<double> sum, diff;
  for (std::size_t i = 0; i < x10.size(); ++i) {
    sum.push_back((x10[i] + x20[i]) / 2);   // (3) summand
    diff.push_back((x10[i] - x20[i]) / 2);  // (4) summand
  }
  BiasBaseError r;
  double s = 0, d = 0;
  for (std::size_t i = 0; i < sum.size(); ++i) {
    s += sum[i];
    d += diff[i];
  }
  const double n = static_cast<double>(sum.size());
  r.bias = s / n;
  // Sign rule: g_dA enters (1) with + when mean(x10) > mean(x20); it is quoted positive.
  r.sign_u10 = d >= 0 ? +1 : -1;
  r.base_error = std::abs(d / n);
  if (sum.size() >= 2) {
    r.bias_ci_half = analysis::gost_summary(sum).ci_half;
    r.base_ci_half = analysis::gost_summary(diff).ci_half;
  }
  return r;
}

std::optional<std::size_t> accuracy_class(const std::vector<AccuracyClass>& classes, double b) {
  for (std::size_t i = 0; i < classes.size(); ++i)
    if (b <= classes[i].max_b_g) return i + 1;
  return std::nullopt;
}

void declare_values(const Profile& p, MeasurementSet& v) {
  auto d = [&](const char* name, const char* unit) { v.declare(name, unit, limit(p, name)); };
  d("bias", "g");
  d("base_error", "g");
  d("in_run_b_gost_100s", "g");
  d("in_run_b_gost_200s", "g");
  for (std::size_t k = 2; k < p.in_run_blocks_s.size(); ++k)
    v.declare(fmt::format("in_run_b_gost_{}s", p.in_run_blocks_s[k]), "g");
  d("in_run_b_allan", "g");
  d("tau_cp", "s");
  d("q", "g*h");
  d("n", "g*h^0.5");
  d("k", "g/h^0.5");
  d("r", "g/h");
  d("in_run_b_allan_filtered", "g");
  d("rms_unfiltered", "g");
  d("rms_filtered", "g");
  d("bandwidth_0p5", "Hz");
  d("settling_time", "s");
  d("accuracy_class", "-");
}

void bring_up(PhaseContext& ctx, const Profile& p, const RunOptions& opt) {
  ctx.dev.io.set_lamp(Lamp::Ready, false);
  ctx.dev.io.set_lamp(Lamp::Running, true);
  if (ctx.dev.io.estop_active()) throw AbortedError("e-stop/interlock is open: close it before starting");
  ctx.log->info("DUT power on ({})", ctx.dev.io.describe());
  ctx.dev.io.set_dut_power(true);
  ctx.dev.clock.sleep_for(1.0, ctx.cancel);  // power-up: the loop captures the pendulum
  const DutInfo info = ctx.dev.dut.info(ctx.cancel);
  ctx.log->info("DUT serial {} firmware {} temperature {:.1f} C rate {} Hz", info.serial, info.firmware,
                info.temperature_c, info.output_rate_hz);
  if (opt.expected_serial && *opt.expected_serial != info.serial)
    throw ConfigError(fmt::format("DUT reports serial '{}', expected '{}' (--serial)", info.serial, *opt.expected_serial));
  if (std::abs(info.output_rate_hz - p.rate_hz) > 1e-6 * p.rate_hz)
    throw ConfigError(fmt::format("DUT streams at {} Hz, profile '{}' expects rate_hz = {}", info.output_rate_hz, p.name,
                                  p.rate_hz));
  ctx.state["serial"] = info.serial;
  ctx.state["dut"] = {{"serial", info.serial}, {"firmware", info.firmware}, {"temperature_c", info.temperature_c}};
  ctx.log->info("output filter: {} ({} section(s) at {} Hz, {})", p.filter_name, p.filter.sections.size(),
                p.filter.rate_hz, p.filter.enabled ? "on" : "off");
  ctx.dev.dut.set_filter(p.filter, ctx.cancel);
  ctx.log->info("homing table ({})", ctx.dev.table.describe());
  ctx.dev.table.home(ctx.cancel);
}

std::vector<Phase> build_phases(const Profile& p) {
  std::vector<Phase> ph;
  const double move_s = 5.0;  // planning allowance for a 180 deg move
  for (std::size_t i = 0; i < p.order.size(); ++i) {
    ph.push_back({run_id(i, p.order[i]),
                  fmt::format("run {} of {} at {}: {} s (procedure A)", i + 1, p.order.size(), to_string(p.order[i]),
                              p.run_s),
                  p.run_s + p.settle_s + move_s, [&p, i](PhaseContext& c) { phase_run(c, p, i); }});
  }
  ph.push_back({"bias", "bias and base error, formulas (3), (4)", 0, [&p](PhaseContext& c) { phase_bias(c, p); }});
  ph.push_back({"in-run", fmt::format("in-run test at {}: {} s (procedure B)", to_string(p.in_run_orientation), p.in_run_s),
                p.in_run_s + p.settle_s + move_s, [&p](PhaseContext& c) {
                  const Recorded r = position_and_record(c, p, p.in_run_orientation, p.in_run_s,
                                                         std::string("in-run-") + to_string(p.in_run_orientation));
                  c.state["in_run"] = {{"capture", r.capture}, {"n", r.samples}, {"lost", r.lost}, {"gaps", r.gaps},
                                       {"attempts", r.attempts}};
                }});
  ph.push_back({"in-run-b", "B by the Russian method, (max-min)/2 of block means", 0,
                [&p](PhaseContext& c) { phase_in_run_b(c, p); }});
  ph.push_back({"raw", fmt::format("raw capture at {}: {} s at {} Hz (procedure C)", to_string(p.raw_orientation),
                                   p.raw_s, p.rate_hz),
                p.raw_s + p.settle_s + move_s, [&p](PhaseContext& c) {
                  const Recorded r = position_and_record(c, p, p.raw_orientation, p.raw_s,
                                                         std::string("raw-") + to_string(p.raw_orientation));
                  c.state["raw"] = {{"capture", r.capture}, {"n", r.samples}, {"lost", r.lost}, {"gaps", r.gaps},
                                    {"attempts", r.attempts}};
                }});
  ph.push_back({"allan", "Allan deviation, noise terms, RMS error and PSD of x(t) and y(t)", 0,
                [&p](PhaseContext& c) { phase_raw_analysis(c, p); }});
  ph.push_back({"loop", "closed-loop bandwidth and settling time with the output filter", 0,
                [&p](PhaseContext& c) { phase_loop(c, p); }});
  return ph;
}

}  // namespace rig::acceptance
