#include "plant/dut/filter_select.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

#include <fmt/format.h>

#include "plant/dut/emulated_dut.hpp"
#include "plant/dut/loop_figures.hpp"
#include "analysis/rms.hpp"
#include "design/filter.hpp"
#include "rig/core/errors.hpp"

namespace rig::plant {

namespace {

std::string butter_name(int order, double fc) {
  std::ostringstream os;
  os << "butter" << order << "@" << fc;
  return os.str();
}

double rms_about_mean(const std::vector<double>& v) {
  double m = 0;
  for (double e : v) m += e;
  m /= static_cast<double>(v.size());
  std::vector<double> d(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) d[i] = v[i] - m;
  return analysis::rms(d);
}

double emulated_rms(const DutParams& p, const FilterConfig& f, const FilterSelectOptions& opt) {
  EmulatedDut dut(p, opt.seed);
  dut.set_filter(f);
  std::vector<double> y(static_cast<std::size_t>(opt.rms_seconds * dut.output_rate_hz()));
  for (double& v : y) {
    double x;
    dut.next(x, v);
  }
  return rms_about_mean(y);
}

}  // namespace

FilterConfig filter_by_name(const std::string& name, double rate_hz) {
  if (name == "paper") {
    FilterConfig f = design::paper_wf();
    f.rate_hz = rate_hz;
    return f;
  }
  if (name == "none") {
    FilterConfig f;
    f.enabled = false;
    f.rate_hz = rate_hz;
    return f;
  }
  // "butter", one digit N, "@", a decimal number FC and nothing else: a stream read took
  // butter02@500 for order 2 and " 500" for FC (a review).
  const std::string_view rest = name.rfind("butter", 0) == 0 ? std::string_view(name).substr(6) : std::string_view();
  double fc = 0;
  const char* const fc_end = rest.data() + rest.size();
  const auto read_fc = [&] {
    const auto [stop, ec] = std::from_chars(rest.data() + 2, fc_end, fc);
    // A number past a double's range (1e309, 1e-400) is a cut-off out of range, named as typed by
    // the range check, not a syntax error (a review).
    if (ec == std::errc::result_out_of_range) fc = 0;
    return (ec == std::errc() || ec == std::errc::result_out_of_range) && stop == fc_end;
  };
  if (rest.size() < 3 || rest[0] < '1' || rest[0] > '9' || rest[1] != '@' || !read_fc())
    throw ConfigError("filter '" + name + "': expected paper, none or butterN@FC (e.g. butter2@500)");
  const int order = rest[0] - '0';
  if (order > 4) throw ConfigError(fmt::format("filter '{}': order {}: a Butterworth of order 1 to 4", name, order));
  if (!(fc > 0) || !(fc < rate_hz / 2))
    throw ConfigError(fmt::format("filter '{}': the cut-off {} Hz must be in (0, {}) Hz, below half the loop rate {} Hz",
                                  name, std::string(rest.substr(2)), rate_hz / 2, rate_hz));
  try {
    // A cut-off so low that the sections round to a pole on the unit circle (butter2@1e-300 printed
    // a filter with DC gain nan that set-filter then refused as unstable: a re-test).
    FilterConfig f = design::butterworth_lowpass(order, fc, rate_hz);
    for (const Biquad& b : f.sections)
      if (!stable_section(b) || !std::isfinite(b.b0 + b.b1 + b.b2))
        throw ConfigError(fmt::format("filter '{}': the cut-off {} Hz is too {} for a stable filter in double "
                                      "precision at {} Hz (its poles round onto the unit circle)",
                                      name, std::string(rest.substr(2)),
                                      fc > rate_hz / 4 ? "near half the loop rate" : "low", rate_hz));
    // The filter as the DUT holds it: binary32 coefficients (docs/can-protocol.md). Rounding a1
    // and a2 to 24 bits moves the poles, and near z = 1 changes 1 + a1 + a2, which sets both the
    // DC gain and the cut-off: butter2@1 read DC gain 1 while the DUT's filter has 0.946 (a
    // metrologist's review). A bound, falling as the cut-off rises (not the error as it happened
    // to round, which came and went: a code review): a1 and a2 each move by up to half a binary32
    // ulp, 2^-24 of themselves, so 1 + a1 + a2 by about 2^-24 (|a1| + |a2|) of itself over its
    // size; refused past 10 % over the sections (the cut-off then moves by about half that at
    // most; the figures are the rounded filter's either way).
    double moved = 0;
    for (const Biquad& b : f.sections) moved += 0x1p-24 * (std::fabs(b.a1) + std::fabs(b.a2)) / std::fabs(1 + b.a1 + b.a2);
    if (!(moved <= 1e-1))
      throw ConfigError(fmt::format("filter '{}': the cut-off {} Hz is too low for the DUT's 32-bit float coefficients "
                                    "at {} Hz: its poles sit so near z = 1 that their rounding can move its cut-off "
                                    "by {} (more than the 10 % allowed)",
                                    name, std::string(rest.substr(2)), rate_hz,
                                    moved >= 1 ? std::string("more than 100 %") : fmt::format("about {:.3g} %", 100 * moved)));
    // Each section's numerator scaled after its poles are rounded, so its DC gain stays the
    // design's; every figure is then the filter the DUT runs.
    for (Biquad& b : f.sections) {
      const double dc = (b.b0 + b.b1 + b.b2) / (1 + b.a1 + b.a2);
      const double a1 = static_cast<float>(b.a1), a2 = static_cast<float>(b.a2);
      const double scale = dc * (1 + a1 + a2) / (b.b0 + b.b1 + b.b2);
      b = Biquad{static_cast<float>(b.b0 * scale), static_cast<float>(b.b1 * scale), static_cast<float>(b.b2 * scale),
                 a1, a2};
      if (!stable_section(b))
        throw ConfigError(fmt::format("filter '{}': the cut-off {} Hz is too near half the loop rate for a stable "
                                      "filter in the DUT's 32-bit float coefficients at {} Hz",
                                      name, std::string(rest.substr(2)), rate_hz));
    }
    return f;
  } catch (const std::invalid_argument& e) {
    throw ConfigError("filter '" + name + "': " + e.what());
  }
}

std::vector<double> candidate_cutoffs(const FilterSelectOptions& opt) {
  if (!(opt.fc_step_hz > 0) || !std::isfinite(opt.fc_step_hz))
    throw ConfigError(fmt::format("--fc-step {}: the cut-off step must be a number of Hz > 0", opt.fc_step_hz));
  if (!(opt.fc_min_hz > 0) || !(opt.fc_max_hz >= opt.fc_min_hz) || !std::isfinite(opt.fc_max_hz))
    throw ConfigError(fmt::format("--fc-min {} --fc-max {}: the cut-off range must be 0 < min <= max Hz, finite",
                                  opt.fc_min_hz, opt.fc_max_hz));
  // Each cut-off min + i step, as many as fit up to max with a millionth of a step for the rounding
  // (an absolute 1e-9 Hz took ten cut-offs past a max of 1e-9 Hz, a review), counted once here: a
  // bound of max + step/1e6 overflowed to inf for a max near 1.8e308, and the loop never ended.
  // Each is an emulated run per order: a range of millions would run for days.
  constexpr double kMaxCutoffs = 10000;
  const double count = std::floor((opt.fc_max_hz - opt.fc_min_hz) / opt.fc_step_hz + 1e-6) + 1;
  if (count > kMaxCutoffs)
    throw ConfigError(fmt::format("--fc-min {} --fc-max {} --fc-step {}: more than {:g} cut-offs to try", opt.fc_min_hz,
                                  opt.fc_max_hz, opt.fc_step_hz, kMaxCutoffs));
  std::vector<double> fc(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < fc.size(); ++i) fc[i] = opt.fc_min_hz + static_cast<double>(i) * opt.fc_step_hz;
  return fc;
}

std::vector<FilterCandidate> select_filters(const toml::table* dut_cfg, const FilterSelectOptions& opt) {
  if (!(opt.f_req_hz > 0)) throw ConfigError("--f-req must be positive");
  const std::vector<double> cutoffs = candidate_cutoffs(opt);
  const DutParams p = load_dut_params(dut_cfg, opt.dut_section);
  const double rate = p.loop.loop_rate_hz;

  // A Butterworth cut-off lies below half the loop rate. A range wholly above it asked for no
  // candidate the rig can make: said, not ranked as paper and none alone (they were, silently).
  if (!(cutoffs.front() < rate / 2))
    throw ConfigError(fmt::format("--fc-min {}: every cut-off of the range ({:g} to {:g} Hz) is at or above half the "
                                  "DUT's loop rate, {:g} Hz, where no low-pass cut-off lies: no Butterworth candidate",
                                  opt.fc_min_hz, cutoffs.front(), cutoffs.back(), rate / 2));
  std::vector<FilterCandidate> c;
  if (opt.include_paper) c.push_back({"paper", filter_by_name("paper", rate)});
  if (opt.include_none) c.push_back({"none", filter_by_name("none", rate)});
  for (int order : opt.orders)
    for (const double fc : cutoffs)
      if (fc < rate / 2) try {
          c.push_back({butter_name(order, fc), filter_by_name(butter_name(order, fc), rate)});
        } catch (const ConfigError& e) {  // a cut-off the user did not type: named by the option that made it
          throw ConfigError(fmt::format("--fc-min {}: a candidate of the range: {}", opt.fc_min_hz, e.what()));
        }

  // The recording about its mean: each filter starts from rest, and on an offset its start-up
  // rang into the RMS (1 g added to a recording moved butter4@500 from 6.3e-4 g, rank 1, to
  // 8.5e-3 g, rank 3: a metrologist's review). A linear filter of the centred record differs from
  // the record's only by that start-up on the mean.
  std::vector<double> centred;
  if (opt.recorded_x && !opt.recorded_x->empty()) {
    double m = 0;
    for (double e : *opt.recorded_x) m += e;
    m /= static_cast<double>(opt.recorded_x->size());
    centred.reserve(opt.recorded_x->size());
    for (double e : *opt.recorded_x) centred.push_back(e - m);
  }
  for (FilterCandidate& k : c) {
    const design::LoopFigures f = loop_figures(dut_cfg, k.filter, opt.dut_section);  // criterion 2, from the model
    k.bandwidth_0p5_hz = f.bandwidth_0p5_hz;
    k.settling_time_s = f.settling_time_s;
    k.settled = f.settled;
    k.step_window_s = f.step_window_s;
    k.meets_band = std::abs(k.bandwidth_0p5_hz - opt.f_req_hz) <= opt.band_tol * opt.f_req_hz;
    if (opt.recorded_x) {  // criterion 1 on a recording at the loop rate
      if (opt.recorded_x->empty()) throw ConfigError("the recording is empty");
      k.rms_g = rms_about_mean(design::apply_filter(k.filter, centred));
    } else {
      k.rms_g = emulated_rms(p, k.filter, opt);
    }
  }
  std::stable_sort(c.begin(), c.end(), [&](const FilterCandidate& a, const FilterCandidate& b) {
    if (a.meets_band != b.meets_band) return a.meets_band;
    if (a.meets_band) {
      if (a.rms_g != b.rms_g) return a.rms_g < b.rms_g;
      return a.settling_time_s < b.settling_time_s;
    }
    return std::abs(a.bandwidth_0p5_hz - opt.f_req_hz) < std::abs(b.bandwidth_0p5_hz - opt.f_req_hz);
  });
  for (std::size_t i = 0; i < c.size(); ++i) c[i].rank = static_cast<int>(i + 1);
  return c;
}

}  // namespace rig::plant
