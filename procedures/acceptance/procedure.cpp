#include "procedures/acceptance/procedure.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "analysis/json.hpp"
#include "procedures/acceptance/analysis_doc.hpp"
#include "procedures/acceptance/method.hpp"
#include "procedures/acceptance/loop_phase.hpp"
#include "procedures/acceptance/record.hpp"
#include "procedures/acceptance/state.hpp"
#include "analysis/allan.hpp"
#include "analysis/envelope.hpp"
#include "analysis/rms.hpp"
#include "analysis/gost.hpp"
#include "analysis/noise_terms.hpp"
#include "analysis/psd.hpp"
#include "rig/capture/capture.hpp"
#include "rig/core/dut_link.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/table.hpp"

namespace rig::acceptance {

namespace {

std::optional<std::pair<double, double>> limit(const Profile& p, const std::string& name) {
  auto it = p.limits.find(name);
  if (it == p.limits.end()) return std::nullopt;
  return it->second;
}

std::string run_id(std::size_t i, Orientation o) { return run_phase_id(i + 1, o); }

// A recording's capture as it was written: a file that reads back incomplete or with another
// number of samples was changed after its recording closed it (a review: with stderr closed, the
// progress display was written into the raw capture, and a quarter of it was judged), so the
// values are never computed from it.
capture::Loaded load_capture(PhaseContext& ctx, const Recorded& r) {
  const std::string& rel = r.capture;
  capture::Loaded l = capture::load(ctx.out_dir + "/" + rel);
  if (!l.recovery.complete || l.samples.size() != r.samples)  // no resume either: it refuses such a folder
    throw RecordsChangedError(l.recovery.summary(rel) + "; its recording wrote " + std::to_string(r.samples) +
                              " samples: the file was changed or damaged after it was written, nothing is computed "
                              "from it");
  if (l.samples.empty()) throw HardwareError(rel + ": capture holds no samples");
  return l;
}

// The drift g_dr(t) = x(t) - g_sist -+ g_dA (docs/method.md, after (4)) of a capture at orientation o.
// By value: the callers pass a fresh channel, which is shifted in place (a copy of a 60 min
// channel is 29 MB of fresh pages).
std::vector<double> drift(std::vector<double> d, const DutState& st, Orientation o) {
  if (!st.bias) return d;  // bias phase not run: the offset does not change Allan/B/PSD
  const BiasState& b = *st.bias;
  const double off = b.bias + (o == Orientation::U10 ? b.sign_u10 : -b.sign_u10) * b.base_error;
  for (double& v : d) v -= off;
  return d;
}

void phase_run(PhaseContext& ctx, const Profile& p, DutState& st, std::size_t i) {
  const Orientation o = p.order[i];
  st.runs[i + 1] = RunMean{i + 1, o, position_and_record(ctx, p, o, p.run_s, run_id(i, o), st.serial(), &st.partial_captures)};
}

// Values read from a capture that lost samples (within the profile's max_lost_samples) were
// computed over the samples joined across the gaps: each says so, with the counts.
void note_gaps(PhaseContext& ctx, const Recorded& r) {
  if (r.lost == 0) return;
  ctx.values.note_scope(fmt::format("{} lost {} samples in {} gap(s), joined across them ([procedure] "
                                    "max_lost_samples)",
                                    r.capture, r.lost, r.gaps));
}

void phase_bias(PhaseContext& ctx, const Profile& p, DutState& st) {
  std::vector<double> x10, x20;
  std::vector<std::size_t> runs10, runs20;  // the run numbers of each pair's summands
  for (std::size_t i = 0; i < p.order.size(); ++i) {
    (p.order[i] == Orientation::U10 ? x10 : x20).push_back(st.runs.at(i + 1).rec.mean_x);
    (p.order[i] == Orientation::U10 ? runs10 : runs20).push_back(i + 1);
  }
  const BiasBaseError b = bias_and_base_error(x10, x20);
  st.bias = BiasState{b.bias, b.base_error, b.sign_u10};
  const std::string sign = fmt::format("formula (4); enters x10 with {}", b.sign_u10 > 0 ? "+" : "-");
  if (b.bias_ci_half && b.base_ci_half) {
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    for (std::size_t k = 0; k < runs10.size(); ++k) pairs.emplace_back(runs10[k], runs20[k]);
    ctx.values.set("bias", b.bias,
                   "formula (3), GOST R 8.736 95 % interval" + grubbs_note(*b.bias_gost, pairs, ctx.log.get(), "bias"),
                   b.bias - *b.bias_ci_half, b.bias + *b.bias_ci_half);
    ctx.values.set("base_error", b.base_error, sign + grubbs_note(*b.base_gost, pairs, ctx.log.get(), "base_error"),
                   b.base_error - *b.base_ci_half, b.base_error + *b.base_ci_half);
  } else {  // one U10/U20 pair: the value without an interval, and said so
    const char* one = "; one U10/U20 pair: no interval (GOST R 8.736 takes it from the scatter of two or more)";
    ctx.values.set("bias", b.bias, std::string("formula (3)") + one);
    ctx.values.set("base_error", b.base_error, sign + one);
  }
  // Each run's mean was taken over its capture's samples joined across its gaps: said on both values,
  // as on every value read from a capture (an automation review: only the in-run and raw records said it).
  for (std::size_t i = 0; i < p.order.size(); ++i) note_gaps(ctx, st.runs.at(i + 1).rec);
}

void phase_in_run_b(PhaseContext& ctx, const Profile& p, DutState& st) {
  const capture::Loaded l = load_capture(ctx, st.in_run.value());
  const std::vector<double> x = capture::channel_x(l.samples);
  std::vector<GostBlock> blocks;
  for (const double bs : p.in_run_blocks_s) {
    const auto len = static_cast<std::size_t>(planned_samples(p, bs));
    const analysis::InRunB b = analysis::in_run_b(x, len);
    blocks.push_back({bs, analysis::block_means(x, len), b.value});
    ctx.values.set(gost_value_name(bs), b.value, fmt::format("(max-min)/2 of {} block means of {} s", b.blocks, bs));
  }
  st.in_run_blocks = blocks;
  // The class is read from B of the first block length (the paper's 100 s); its outcome is
  // judged with every other value (required when the profile has classes).
  const std::optional<double> b = blocks.empty() ? std::nullopt : blocks.front().b_g;
  if (!b) {
    ctx.values.set("accuracy_class", std::nullopt, "no B from the first block length");
  } else if (auto c = accuracy_class(p.classes, *b)) {
    ctx.values.set("accuracy_class", static_cast<double>(*c), p.classes[*c - 1].name);
  } else if (p.classes.empty()) {  // `classes = []`: nothing to read a class from (not required then)
    ctx.values.set("accuracy_class", std::nullopt, "the profile has no accuracy classes ([[classes]])");
  } else {
    // B was measured: the class is missing because B is beyond the table, which the verdict says.
    ctx.values
        .set("accuracy_class", std::nullopt,
             fmt::format("B = {:.3g} g; the loosest class, '{}', takes B up to {:.3g} g", *b, p.classes.back().name,
                         p.classes.back().max_b_g))
        .null_verdict = "B exceeds every accuracy class";
  }
  note_gaps(ctx, *st.in_run);
}

// Allan family + noise terms of one channel; writes the passport values.
nlohmann::json allan_channel(PhaseContext& ctx, const Profile& p, const std::vector<double>& d, bool filtered,
                             const std::string& y_filter_note = "") {
  // One model fit (R a candidate on every record; its reason notes a record shorter than the
  // profile's [analysis] r_min_record_s): the passport and analysis.json carry the same fit. An
  // abort is taken within a chunk of work.
  const AllanChannel ch = allan_channel_terms(d, allan_settings(p), [&ctx] { ctx.cancel.throw_if_requested(); });
  const std::vector<analysis::DevPoint>& dev = ch.oadev;
  const analysis::NoiseTerms& nt = ch.terms;
  // A term as the passport value `name`, scaled into its declared unit. A null term's upper
  // limit is restated from `hi` in that unit: analysis' reason quotes it per second, and a
  // reason must state its numbers in its own value's unit.
  auto term_value = [&](const char* name, const char* symbol, const analysis::Term& t, double scale,
                        const std::string& why) {
    if (t.value) {
      ctx.values.set(name, *t.value * scale, why.empty() ? t.reason : why,
                     t.lo ? std::optional<double>(*t.lo * scale) : std::nullopt,
                     t.hi ? std::optional<double>(*t.hi * scale) : std::nullopt);
    } else if (t.hi && !t.reason_without_limit.empty()) {
      ctx.values.set(name, std::nullopt,
                     fmt::format("{}; upper limit {} <= {:.3g} {}", t.reason_without_limit, symbol, *t.hi * scale,
                                 ctx.values.find(name)->unit));
    } else {
      ctx.values.set(name, std::nullopt, t.reason.empty() ? "not identifiable from this record" : t.reason);
    }
  };
  if (!filtered) {
    // B as the profile's [analysis] b_allan says: "paper" (sigma(tau_cp)/0.664; its reason names
    // flat segment, polynomial minimum or least-squares fallback) or "lsq" (the model's B).
    term_value("in_run_b_allan", "B", p.b_allan == "lsq" ? nt.wls.B : nt.B, 1.0, "");
    if (nt.tau_cp_s && nt.b_method == "flat_segment")
      ctx.values.set("tau_cp", *nt.tau_cp_s, nt.B.reason);
    else if (nt.tau_cp_s)
      ctx.values.set("tau_cp", *nt.tau_cp_s, "minimum of the paper's polynomial (no flat segment)");
    else ctx.values.set("tau_cp", std::nullopt, nt.B.reason.empty() ? "no flat segment" : nt.B.reason);
    // IEEE 952 terms quoted per hour (docs/method.md), by noise_terms.hpp's factors: Q g*s -> g*h,
    // N g*s^0.5 -> g*h^0.5, K g/s^0.5 -> g/h^0.5, R g/s -> g/h.
    term_value("q", "Q", nt.Q, analysis::kQToHour, "");
    term_value("n", "N", nt.N, analysis::kNToHour, "");
    term_value("k", "K", nt.K, analysis::kKToHour, "");
    term_value("r", "R", nt.R, analysis::kRToHour, "");
  } else {
    // How B was read too (flat segment, polynomial minimum, least squares), as in_run_b_allan's
    // reason says it: the report labels its interval by it (a review: "±1 σ of the Allan fit"
    // stood on this one's chi-square interval).
    term_value("in_run_b_allan_filtered", "B", nt.B, 1.0,
               "on the filtered output y(t)" + y_filter_note + (nt.B.reason.empty() ? "" : "; " + nt.B.reason));
  }
  return {{"oadev", analysis::dev_to_json(dev)}, {"noise_terms", analysis::noise_terms_to_json(nt)}};
}

void phase_raw_analysis(PhaseContext& ctx, const Profile& p, DutState& st) {
  const capture::Loaded l = load_capture(ctx, st.raw.value());
  ctx.cancel.throw_if_requested();
  const std::vector<double> x = drift(capture::channel_x(l.samples), st, p.raw_orientation);
  const std::vector<double> y = drift(capture::channel_y(l.samples), st, p.raw_orientation);
  // A DUT whose stream carries no y(t) ([dut.stream] without y: every y is NaN) has no filtered
  // output: its y values are null with that reason (failing a profile that limits them), not an
  // analysis error on NaN, exit 4, on every resume alike (an integrator's review).
  const bool has_y = std::any_of(y.begin(), y.end(), [](double v) { return !std::isnan(v); });
  const char* kNoY = "the DUT's stream carries no filtered output y(t) (its [dut.stream] names no y)";
  // The filter y(t) went through, as its capture says: the profile's unless the DUT had no command
  // channel to load it with. Then its y values say so: rms_filtered was judged against the
  // profile's limit as if the profile's filter had made it (a review).
  const std::string filter = l.header.extra.value("filter", std::string());
  const std::string y_filter_note =
      filter.rfind("not set", 0) == 0
          ? " (through the DUT's own filter: the profile's was not loaded, the passport's skipped steps say why)"
          : "";
  nlohmann::json a;
  a["allan"]["x"] = allan_channel(ctx, p, x, false);
  ctx.report(0.45);
  if (has_y) a["allan"]["y"] = allan_channel(ctx, p, y, true, y_filter_note);
  else ctx.values.set("in_run_b_allan_filtered", std::nullopt, kNoY);
  ctx.report(0.9);
  // RMS error of the output (criterion 1), of the drift (bias and base error removed).
  ctx.values.set("rms_unfiltered", analysis::rms(x), "RMS of x(t) drift over the raw capture");
  if (has_y) ctx.values.set("rms_filtered", analysis::rms(y), "RMS of y(t) drift over the raw capture" + y_filter_note);
  else ctx.values.set("rms_filtered", std::nullopt, kNoY);
  for (const auto& [ch, v] : {std::pair{"x", &x}, std::pair{"y", &y}}) {
    if (v == &y && !has_y) continue;
    analysis::WelchOptions wo;
    wo.poll = [&ctx] { ctx.cancel.throw_if_requested(); };
    const analysis::Psd psd = analysis::welch(*v, p.rate_hz, wo);
    a["psd"][ch] = analysis::psd_to_json(psd, analysis::find_peaks(psd));
  }
  const std::size_t n_ts = std::min<std::size_t>(x.size(), static_cast<std::size_t>(2 * p.rate_hz));
  a["timeseries"] = {{"rate_hz", p.rate_hz},
                     {"t0_s", 0.0},
                     {"x", std::vector<double>(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(n_ts))},
                     {"y", has_y ? nlohmann::json(std::vector<double>(y.begin(), y.begin() + static_cast<std::ptrdiff_t>(n_ts)))
                                 : nlohmann::json(nullptr)},
                     {"note", "first 2 s of the raw capture (drift: bias and base error removed)"}};
  // For the report: the whole capture as block means with the raw min/max, the bounds' level,
  // and the device time the run took up to here.
  a["output_envelope"] = analysis::envelope_to_json(analysis::block_envelope(x, p.rate_hz, 1000),
                                                    analysis::block_envelope(has_y ? std::span<const double>(y)
                                                                                   : std::span<const double>(),
                                                                             p.rate_hz, 1000),
                                                    "raw capture, drift: bias and base error removed");
  a["allan"]["confidence"] = p.confidence;
  st.analysis = a;
  note_gaps(ctx, *st.raw);
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
    r.bias_gost = analysis::gost_summary(sum);
    r.base_gost = analysis::gost_summary(diff);
    r.bias_ci_half = r.bias_gost->ci_half;
    r.base_ci_half = r.base_gost->ci_half;
  }
  return r;
}

// What GOST R 8.736's repeated Grubbs test found among the pairs' summands, for the value's
// reason: an outlier is reported, not removed (the value is of every pair, as recorded), so a
// technician can look at that pair's runs. pairs[k]: the k-th pair's run numbers (U10, U20).
std::string grubbs_note(const analysis::GostSummary& g, const std::vector<std::pair<std::size_t, std::size_t>>& pairs,
                        spdlog::logger* log, const char* value) {
  const double significance = 1 - g.confidence;
  if (g.n < 3) return fmt::format("; {} pairs: no Grubbs test (it needs 3)", g.n);
  if (g.outliers.empty())
    return g.sd == 0 ? fmt::format("; Grubbs ({:g} %): no outlier among {} pairs (all alike)", 100 * significance, g.n)
                     : fmt::format("; Grubbs ({:g} %): no outlier among {} pairs (G {:.3f} <= {:.3f})",
                                   100 * significance, g.n, g.grubbs_stat, g.grubbs_crit);
  std::vector<std::string> named;
  for (std::size_t k : g.outliers)
    named.push_back(fmt::format("pair {} (runs {} U10, {} U20)", k + 1, pairs[k].first, pairs[k].second));
  const std::string note =
      fmt::format("; Grubbs ({:g} %): outlier{} {} among {} pairs (first G {:.3f} > {:.3f}), kept in the value "
                  "(GOST R 8.736: reported, not removed)",
                  100 * significance, g.outliers.size() > 1 ? "s" : "", fmt::join(named, ", "), g.n, g.grubbs_stat,
                  g.grubbs_crit);
  if (log) log->warn("{}: {}", value, note.substr(2));
  return note;
}

std::optional<std::size_t> accuracy_class(const std::vector<AccuracyClass>& classes, double b) {
  for (std::size_t i = 0; i < classes.size(); ++i)
    if (b <= classes[i].max_b_g) return i + 1;
  return std::nullopt;
}

void declare_values(const Profile& p, const std::vector<Phase>& phases, MeasurementSet& v) {
  // Passport order: every phase's measures in phase order, then the accuracy class (the
  // passport's conclusion). A name declared twice is a programming error.
  const MeasurementSpec* klass = nullptr;
  std::vector<std::string> seen;
  for (const Phase& ph : phases)
    for (const MeasurementSpec& m : ph.measures) {
      if (std::find(seen.begin(), seen.end(), m.name) != seen.end())
        throw std::logic_error("measurement '" + m.name + "' declared by two phases");
      seen.push_back(m.name);
      if (m.name == "accuracy_class") klass = &m;
      else v.declare(m, limit(p, m.name));
    }
  // With a class table, the class is required: a B that exceeds every class fails the run.
  if (klass) v.declare(*klass, limit(p, klass->name), !p.classes.empty());
}

DutIdentity identity_without_commands(const Profile& p, const RunOptions& opt, const std::string& why) {
  if (!opt.expected_serial || opt.expected_serial->empty())
    throw ConfigError("the DUT cannot report its serial (" + why + "): give it with --serial");
  DutIdentity id{*opt.expected_serial, "", std::nullopt, {}};
  id.skipped = {
      {"identify", "serial taken from --serial; firmware version, temperature and output rate not read (" + why + ")"},
      {"set output filter", fmt::format("the profile's filter '{}' was not loaded: y(t) is the output of whatever filter "
                                        "the DUT runs ({})", p.filter_name, why)},
      {"loop test", "bandwidth_0p5 and settling_time not measured (" + why + ")"}};
  return id;
}

void bring_up(PhaseContext& ctx, const Profile& p, const RunOptions& opt, DutState& st) {
  ctx.dev.io.set_lamp(Lamp::Ready, false);
  ctx.dev.io.set_lamp(Lamp::Running, true);
  if (ctx.dev.io.estop_active()) throw AbortedError("e-stop/interlock is open: close it before starting");
  ctx.log->info("DUT power on ({})", ctx.dev.io.describe());
  if (ctx.progress) ctx.progress->log("  DUT power on");  // what the operator's answers started, said as it happens
  ctx.dev.io.set_dut_power(true);
  ctx.dev.clock.sleep_for(1.0, ctx.cancel);  // power-up: the loop captures the pendulum
  const DutCommandChannel commands = ctx.dev.dut.command_channel();
  if (!commands.available) {
    st.dut = identity_without_commands(p, opt, commands.reason);
    for (const SkippedStep& k : st.dut->skipped) ctx.log->warn("skipped: {}: {}", k.step, k.reason);
  } else {
    const DutInfo info = ctx.dev.dut.info(ctx.cancel);
    // The rate is the one the DUT (or its stream layout) declares, checked against the profile
    // below; each capture's sample count over its device time is what the stream delivered.
    ctx.log->info("DUT serial {} firmware {} temperature {:.1f} C declared rate {} Hz", info.serial, info.firmware,
                  info.temperature_c, info.output_rate_hz);
    if (opt.expected_serial && *opt.expected_serial != info.serial)
      throw ConfigError(fmt::format("DUT reports serial '{}', expected '{}' (--serial)", info.serial, *opt.expected_serial));
    // A resume restores the identity its checkpoint was made with: the completed phases measured
    // that DUT, so another one mounted since must not finish its passport (a hardware run
    // started without --serial has nothing else to check it by).
    if (st.dut && !st.dut->serial.empty() && st.dut->serial != info.serial)
      throw ConfigError(fmt::format("DUT reports serial '{}', but the run being resumed measured '{}' in its completed "
                                    "phases: mount that DUT, or start a new run",
                                    info.serial, st.dut->serial));
    if (std::abs(info.output_rate_hz - p.rate_hz) > 1e-6 * p.rate_hz)
      throw ConfigError(fmt::format("DUT streams at {} Hz, profile '{}' expects rate_hz = {}", info.output_rate_hz, p.name,
                                    p.rate_hz));
    st.dut = DutIdentity{info.serial, info.firmware, info.temperature_c, {}};
    ctx.log->info("output filter: {} ({} section(s) at {} Hz, {})", p.filter_name, p.filter.sections.size(),
                  p.filter.rate_hz, p.filter.enabled ? "on" : "off");
    ctx.dev.dut.set_filter(p.filter, ctx.cancel);
  }
  ctx.log->info("homing table ({})", ctx.dev.table.describe());
  if (ctx.progress) ctx.progress->log("  homing the table");
  ctx.dev.table.home(ctx.cancel);
  // Both angles against the travel the drive reports, before anything is recorded: a rig-v1
  // drive's limits are known only now, and a U20 outside them ended the run at its first U20
  // move, the U10 recordings spent (a review: the dry run could not say).
  if (const auto travel = ctx.dev.table.travel_deg(ctx.cancel))
    for (const Orientation o : {Orientation::U10, Orientation::U20}) {
      const double deg = table_angle(p, o);
      if (deg < travel->first || deg > travel->second)
        throw ConfigError(fmt::format("{} at {:g}°: outside the table's travel [{:g}°, {:g}°] that {} reports; nothing "
                                      "recorded (change the angle, [procedure] u10_deg / u20_deg, or the drive's limits)",
                                      to_string(o), deg, travel->first, travel->second, ctx.dev.table.describe()));
    }
}

double TableTiming::move_s(double from_deg, double to_deg) const {
  return trapezoid_time(to_deg - from_deg, velocity_dps, accel_dps2) + drive_settle_s + settle_s + poll_s;
}

std::vector<Phase> build_phases(const Profile& p, ProcedureState& state, const TableTiming& table,
                                const DutAbilities& dut) {
  DutState& st = state.slot(0);  // a multi-DUT fixture runs each phase over its slots
  std::vector<Phase> ph;
  // A recording's planned device time (position_and_record): the move from where the previous
  // recording left the table, the profile's settle, the record itself.
  double table_at = table.home_deg;
  auto recording_s = [&](Orientation o, double seconds) {
    const double to = table_angle(p, o);
    const double s = table.move_s(table_at, to) + p.settle_s + seconds;
    table_at = to;
    return s;
  };
  for (std::size_t i = 0; i < p.order.size(); ++i) {
    ph.push_back({run_id(i, p.order[i]),
                  fmt::format("run {} of {} at {}: {} s (procedure A)", i + 1, p.order.size(), to_string(p.order[i]),
                              p.run_s),
                  recording_s(p.order[i], p.run_s), [&p, &st, i](PhaseContext& c) { phase_run(c, p, st, i); }});
  }
  ph.push_back({"bias", "bias and base error, formulas (3), (4)", 0, [&p, &st](PhaseContext& c) { phase_bias(c, p, st); },
                {{"bias", "g", "Bias g_сист, formula (3)"},
                 {"base_error", "g", "Base error g_δA, formula (4)"}},
                true});
  ph.push_back({"in-run", fmt::format("in-run test at {}: {} s (procedure B)", to_string(p.in_run_orientation), p.in_run_s),
                recording_s(p.in_run_orientation, p.in_run_s), [&p, &st](PhaseContext& c) {
                  st.in_run = position_and_record(c, p, p.in_run_orientation, p.in_run_s, in_run_phase_id(p),
                                                  st.serial(), &st.partial_captures);
                }});
  std::vector<MeasurementSpec> gost;
  for (const double bs : p.in_run_blocks_s)
    gost.push_back({gost_value_name(bs), "g",
                    fmt::format("In-run B, (max − min)/2 of {:g} s averages (GOST)", bs)});
  gost.push_back({"accuracy_class", "-",
                  fmt::format("Accuracy class from B of {:g} s averages", p.in_run_blocks_s.empty() ? 0.0 : p.in_run_blocks_s[0])});
  ph.push_back({"in-run-b", "B by the Russian method, (max-min)/2 of block means", 0,
                [&p, &st](PhaseContext& c) { phase_in_run_b(c, p, st); }, gost, true});
  ph.push_back({"raw", fmt::format("raw capture at {}: {} s at {} Hz (procedure C)", to_string(p.raw_orientation),
                                   p.raw_s, p.rate_hz),
                recording_s(p.raw_orientation, p.raw_s), [&p, &st](PhaseContext& c) {
                  st.raw = position_and_record(c, p, p.raw_orientation, p.raw_s, raw_phase_id(p), st.serial(),
                                               &st.partial_captures);
                }});
  ph.push_back({"allan", "Allan deviation, noise terms, RMS error and PSD of x(t) and y(t)", 0,
                [&p, &st](PhaseContext& c) { phase_raw_analysis(c, p, st); },
                {{"in_run_b_allan", "g", "In-run B from Allan deviation, σ(τ_ср)/0.664"},
                 {"tau_cp", "s", "τ_ср, the averaging time in_run_b_allan is read at"},
                 {"q", "g*h", "Quantisation Q"},
                 {"n", "g*h^0.5", "Random walk N"},
                 {"k", "g/h^0.5", "Rate random walk K"},
                 {"r", "g/h", "Rate ramp R"},
                 {"in_run_b_allan_filtered", "g", "In-run B from Allan deviation, filtered output y(t)"},
                 {"rms_unfiltered", "g", "RMS error x̂ of x(t)"},
                 {"rms_filtered", "g", "RMS error x̂ of y(t)"}},
                true});
  // Its title says what the plan holds: a DUT that cannot run it is not stepped (the plan read
  // "5 step(s)" beside "skipped: loop test": an integrator's review).
  ph.push_back({"loop", dut.runs_loop_test()
                            ? fmt::format("loop test on the DUT: {} step(s) of {:g} g inside its loop, recorded",
                                          p.loop_steps, p.loop_amplitude_g)
                            : std::string(!dut.commands ? "loop test: not run (the DUT has no command channel)"
                                                        : "loop test: not run (the DUT's firmware has none)"),
                // the steps at the loop's rate, the rate the output filter runs at in the DUT; a DUT
                // that cannot run it takes no device time (the plan said 2 s or more: a review)
                !dut.runs_loop_test() ? 0.0
                : p.loop_steps * loop_step_nominal_s(p.loop_record_s,
                                                   static_cast<std::size_t>(std::lround(p.loop_record_s * p.filter.rate_hz))),
                [&p, &st](PhaseContext& c) { phase_loop_test(c, p, st); }});
  ph.back().uses_devices = dut.link_loop_test_refusal.empty();
  ph.push_back({"loop-figures",
                dut.runs_loop_test() ? "closed-loop bandwidth and settling time with the output filter, from the loop "
                                       "test's records"
                : p.design_model     ? "closed-loop bandwidth and settling time: the DUT type's design model (" +
                                       p.design_model->source + "), not measured (no loop test)"
                                     : std::string("closed-loop bandwidth and settling time: not measured (no loop "
                                                   "test, no [dut.design]): null"),
                0,
                [&p, &st](PhaseContext& c) { phase_loop_figures(c, p, st); },
                {{"bandwidth_0p5", "Hz", "Closed-loop bandwidth with the filter, 0.5 level, measured by the DUT's loop test"},
                 {"settling_time", "s", "Closed-loop settling time, 1 g step, 5 % band, measured by the DUT's loop test"}},
                true});
  // Every phase that uses the devices leaves the rig's clock in the state (analysis.json's
  // device_time_s): the phases that only compute, which a resume runs again, never move it.
  for (Phase& phase : ph)
    if (!phase.from_records)
      phase.run = [&st, run = std::move(phase.run)](PhaseContext& c) {
        run(c);
        st.device_time_s = c.dev.clock.now_s();
      };
  return ph;
}

}  // namespace rig::acceptance
