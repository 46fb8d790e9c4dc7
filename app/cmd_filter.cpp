// `rig filter`: the output filter W_f(z) judged by the paper's two criteria (docs/method.md):
//   rig filter select --f-req 500   ranks Butterworth orders 1-4 over a range of cut-offs and
//                                   the paper's W_f(z): bandwidth (0.5 level) -> f_req and
//                                   settling time -> min from the DUT's closed-loop model,
//                                   RMS -> min on emulated output (or a recording of x).
//   rig filter show --filter NAME   closed-loop figures and curves with one filter.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "plant/dut/filter_select.hpp"
#include "procedures/acceptance/profile.hpp"
#include "plant/dut/loop_figures.hpp"
#include "plant/dut/params.hpp"
#include "plant/emulated/world.hpp"
#include "app/analyze_input.hpp"
#include "app/commands.hpp"
#include "app/existing_path.hpp"
#include "app/number_option.hpp"
#include "app/output_file.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::cli {

namespace {

using nlohmann::json;

// The DUT overrides of a profile: its [plant.dut] table, or the whole file when it has none.
struct DutConfig {
  toml::table file;
  const toml::table* dut = nullptr;
  std::string section = "plant.dut";  // what errors call `dut`: "" for a DUT file, whose [loop] is [loop]
  bool own_filter = false;             // the file itself has a [filter] (not only its base's)
};
// --dut: a profile (its [profile], [procedure], [plant] or `base`) gives its [plant.dut], its
// base's merged in, or none (the built-in DUT); a DUT TOML is the DUT's table itself. A profile
// without [plant.dut] was read whole as a DUT table: profiles/paper.toml was "unknown key
// 'analysis' in [plant.dut]" (a code review).
void load_dut(const std::string& path, DutConfig& c) {
  if (path.empty()) return;
  c.file = cfg::parse_file(path);
  c.own_filter = c.file.contains("filter");  // before a profile's base is merged in
  for (const char* key : {"profile", "procedure", "plant", "base"})
    if (c.file.contains(key)) {
      c.file = acceptance::resolve_profile_file(std::move(c.file));
      // A whole profile (its own or its base's [profile]) held to its rules, as `rig run` holds it:
      // a typo outside [plant.dut] ([plant.dutt], a top-level key) left the built-in DUT in use
      // without a word (a re-test). A file of [plant.dut] overrides alone is no profile to parse.
      if (c.file.contains("profile")) acceptance::parse_profile(c.file, path);
      const toml::table* plant = cfg::get_table(c.file, "plant");
      if (plant) plant::check_plant_keys(*plant);
      c.dut = plant ? cfg::get_table(*plant, "dut") : nullptr;
      return;
    }
  c.dut = &c.file;
  c.section.clear();
}

// The recording: the `rig analyze --input text` format, read by its reader (this one took the
// number a line starts with and dropped the rest: a decimal comma read every value as 0, an
// instrument engineer's review).
std::vector<double> read_recording(const std::string& path) {
  check_input_path(path, "text");
  std::vector<double> v = read_text(path);
  if (v.empty()) throw ConfigError(path + ": no values");
  return v;
}

std::string fmt_g(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

// `filter select --seconds`'s most: an hour of emulated output per candidate.
constexpr double kMaxSelectSeconds = 3600;

// `v` where `known`, else null: a settling time and its lower bound are each one or the other.
json number_if(bool known, double v) { return known ? json(v) : json(nullptr); }

json candidate_json(const plant::FilterCandidate& c) {
  json s = json::array();
  for (const Biquad& b : c.filter.sections) s.push_back({b.b0, b.b1, b.b2, b.a1, b.a2});
  return {{"rank", c.rank},
          {"name", c.name},
          {"bandwidth_0p5_hz", c.bandwidth_0p5_hz},
          {"settling_time_s", number_if(c.settled, c.settling_time_s)},
          {"settled", c.settled},
          {"settling_time_at_least_s", number_if(!c.settled, c.settling_time_s)},
          {"step_window_s", c.step_window_s},
          {"rms_g", c.rms_g},
          {"meets_band", c.meets_band},
          {"sections", c.filter.enabled ? s : json::array()},
          {"rate_hz", c.filter.rate_hz}};
}

// A settling time in ms below a second, else in s; one the model's longest step did not reach
// is given as what it is, a lower bound.
std::string settling_text(const design::LoopFigures& lf) {
  if (!lf.settled)
    return fmt::format("at least {:g} s (not settled in the first half of the model's longest step, {:g} s)",
                       lf.settling_time_s, lf.step_window_s);
  return lf.settling_time_s < 1 ? fmt::format("{:g} ms", lf.settling_time_s * 1e3)
                                : fmt::format("{:g} s", lf.settling_time_s);
}
// The select table's bandwidth, Hz: one decimal from 10 Hz, four digits below (a cut-off under
// 0.05 Hz printed 0.0).
std::string bandwidth_cell(double hz) { return hz >= 10 ? fmt::format("{:.1f}", hz) : fmt::format("{:.4g}", hz); }
// The select table's settling time, ms: '>' before a lower bound.
std::string settling_cell(const plant::FilterCandidate& c) {
  return fmt::format("{}{:.3f}", c.settled ? "" : ">", c.settling_time_s * 1e3);
}

// Every step of the write checked: `--json /dev/full` ended in exit 0 with no JSON (a review).
void write_json(const std::string& path, const json& j, const std::string& what) {
  write_output_file(path, j.dump(2) + "\n", what);
}

// Orders are checked one by one by their option's range; the same order twice would be ranked
// against itself, every cut-off evaluated twice.
void check_orders(const std::vector<int>& orders) {
  for (std::size_t i = 0; i < orders.size(); ++i)
    for (std::size_t k = 0; k < i; ++k)
      if (orders[k] == orders[i])
        throw ConfigError("--orders: " + std::to_string(orders[i]) + " is given twice (each order is tried once)");
}

// --orders' items as typed: "1,2" is two; an empty item ("1,,2", "1,") is kept as "" for the
// option's check to name.
std::vector<std::string> order_items(const std::string& text) {
  std::vector<std::string> items;
  for (std::size_t from = 0; from <= text.size();) {
    const std::size_t comma = std::min(text.find(',', from), text.size());
    items.push_back(text.substr(from, comma - from));
    from = comma + 1;
  }
  return items;
}

// The paper's W_f(z) is its MCU's at 10 kHz: at another loop rate the same coefficients are
// another filter (its poles, in Hz, move with the rate), which "paper" would otherwise stand for.
std::string paper_rate_note(double loop_rate_hz) {
  const double paper_hz = design::paper_wf().rate_hz;
  if (loop_rate_hz == paper_hz) return "";
  return fmt::format("the paper's W_f(z) coefficients are its {} Hz loop's; this DUT's loop runs at {} Hz, where they "
                     "are another filter (its corner moves with the rate): the figures are of that filter",
                     paper_hz, loop_rate_hz);
}

struct SelectArgs {
  double f_req = 500, tol = 5, fc_min = 300, fc_max = 1500, fc_step = 50, seconds = 60;
  std::vector<int> orders{1, 2, 3, 4};
  std::vector<std::string> orders_text;  // --orders as given (checked by its option): replaces `orders`
  uint64_t seed = 1;
  std::string dut_file, recorded, json_out;
  std::size_t top = 15;
};

void run_select(SelectArgs a) {
  if (!a.orders_text.empty()) {
    a.orders.clear();
    for (const std::string& text : a.orders_text)
      for (const std::string& item : order_items(text)) a.orders.push_back(static_cast<int>(*whole_number(item, 1, 4)));
  }
  check_orders(a.orders);
  if (!a.json_out.empty()) check_output_file(a.json_out, "rig filter select --json");  // before the work
  DutConfig dc;
  load_dut(a.dut_file, dc);
  plant::FilterSelectOptions o;
  o.f_req_hz = a.f_req;
  o.band_tol = a.tol / 100;
  o.orders = a.orders;
  o.fc_min_hz = a.fc_min;
  o.fc_max_hz = a.fc_max;
  o.fc_step_hz = a.fc_step;
  o.rms_seconds = a.seconds;
  o.seed = a.seed;
  std::vector<double> rec;
  if (!a.recorded.empty()) {
    rec = read_recording(a.recorded);
    o.recorded_x = &rec;
  }
  o.dut_section = dc.section;
  const std::vector<plant::FilterCandidate> c = plant::select_filters(dc.dut, o);
  const double rate_hz = plant::load_dut_params(dc.dut, dc.section).loop.loop_rate_hz;
  std::cout << "criterion 2 from the closed-loop model; criterion 1 (RMS) on "
            << (a.recorded.empty() ? "emulated output, " + fmt_g(a.seconds) + " s, seed " + std::to_string(a.seed)
                                   : a.recorded)
            << "\nband: |f_0.5 - " << a.f_req << " Hz| <= " << a.tol << " %\n\n";
  std::cout << std::left << std::setw(5) << "rank" << std::setw(16) << "filter" << std::right << std::setw(12)
            << "f_0.5, Hz" << std::setw(14) << "t_settle, ms" << std::setw(14) << "RMS, g" << "  band\n";
  for (std::size_t i = 0; i < c.size() && i < a.top; ++i)
    std::cout << std::left << std::setw(5) << c[i].rank << std::setw(16) << c[i].name << std::right
              << std::setw(12) << bandwidth_cell(c[i].bandwidth_0p5_hz) << std::setw(14) << settling_cell(c[i])
              << std::scientific << std::setprecision(4)
              << std::setw(14) << c[i].rms_g << "  " << (c[i].meets_band ? "yes" : "no") << std::defaultfloat
              << "\n";
  // What the table cannot say, in the text and in the JSON alike (a re-test: a script saw none).
  std::vector<std::string> notes;
  const auto note = [&](const std::string& text) {
    std::cout << "\nnote: " << text << "\n";
    notes.push_back(text);
  };
  // Cut-offs the range gave that no low-pass filter has (at or above half the loop rate): left
  // out of the table, said (they were dropped silently, a review).
  const std::vector<double> cutoffs = plant::candidate_cutoffs(o);
  const auto above = std::find_if(cutoffs.begin(), cutoffs.end(), [&](double fc) { return !(fc < rate_hz / 2); });
  if (above != cutoffs.end())
    note(fmt::format("{} cut-off(s) of the range ({:g} to {:g} Hz) are at or above half the DUT's loop rate, {:g} Hz, "
                     "and are not candidates",
                     cutoffs.end() - above, *above, cutoffs.back(), rate_hz / 2));
  // Rank 1 of a table with no candidate in the band read as a choice (a re-test).
  if (std::none_of(c.begin(), c.end(), [](const plant::FilterCandidate& k) { return k.meets_band; }))
    note(fmt::format("no candidate is in the band (|f_0.5 - {} Hz| <= {} %): the ranks are by the distance from it, "
                     "no candidate is a choice; try other cut-offs (--fc-min, --fc-max, --fc-step), --orders or --tolerance",
                     a.f_req, a.tol));
  for (const auto& k : c)
    if (k.name == "paper") {
      std::cout << "\nthe paper's W_f(z): rank " << k.rank << " of " << c.size() << "\n";
      if (const std::string n = paper_rate_note(rate_hz); !n.empty()) note(n);
    }
  // The RMS column is over a window: a candidate whose own step takes a good part of it reads its
  // start-up (a sub-Hz filter over 1 s read RMS 0 and ranked first, a review). A lower bound
  // counts only where it already passes a tenth of the window; the advice only where it can be
  // followed (--seconds is at most 3600: a re-test was told to give 4096).
  const double window_s = a.recorded.empty() ? a.seconds : static_cast<double>(rec.size()) / rate_hz;
  const plant::FilterCandidate* slowest = nullptr;
  std::size_t slow = 0, in_band = 0;
  for (const auto& k : c)
    if (10 * k.settling_time_s > window_s) {
      ++slow;
      in_band += k.meets_band;
      if (!slowest || k.settling_time_s > slowest->settling_time_s) slowest = &k;
    }
  if (slowest) {
    const double need_s = 10 * slowest->settling_time_s;
    const std::string advice =
        !a.recorded.empty() ? "a recording at least ten times their settling time long would rank them"
        : slowest->settled && need_s <= kMaxSelectSeconds
            ? fmt::format("give --seconds {:g} or more (ten times the slowest's)", std::ceil(need_s))
            : fmt::format("ten times the slowest's is past --seconds' {:g} s: a recording that long (--recorded) "
                          "would rank them",
                          kMaxSelectSeconds);
    note(fmt::format("{} candidate(s), {} of them in the band, settle in more than a tenth of the RMS window ({:g} s "
                     "of {}): their RMS is of the filter's start-up as much as of the noise (the slowest, {}: {}{:g} "
                     "s); {}",
                     slow, in_band, window_s, a.recorded.empty() ? "emulated output" : "the recording", slowest->name,
                     slowest->settled ? "" : "at least ", slowest->settling_time_s, advice));
  }
  if (!a.json_out.empty()) {
    json j = {{"f_req_hz", a.f_req}, {"band_tol_pct", a.tol}, {"candidates", json::array()}, {"notes", notes}};
    for (const auto& k : c) j["candidates"].push_back(candidate_json(k));
    write_json(a.json_out, j, "rig filter select --json");
  }
}

struct ShowArgs {
  std::string filter = "paper", dut_file, json_out;
};

void run_show(const ShowArgs& a) {
  if (!a.json_out.empty()) check_output_file(a.json_out, "rig filter show --json");
  DutConfig dc;
  load_dut(a.dut_file, dc);
  const plant::DutParams p = plant::load_dut_params(dc.dut, dc.section);
  const FilterConfig f = plant::filter_by_name(a.filter, p.loop.loop_rate_hz);
  const design::LoopFigures lf = plant::loop_figures(dc.dut, f, dc.section);
  // The design model's figures, labelled so: a DUT's own are measured by `rig run`'s loop test.
  std::cout << "filter " << a.filter << " at " << p.loop.loop_rate_hz << " Hz (model: the DUT's design loop, not a measurement)\n"
            << "closed-loop bandwidth (0.5 level): " << lf.bandwidth_0p5_hz << " Hz\n"
            << "closed-loop bandwidth (-3 dB):     " << lf.bandwidth_3db_hz << " Hz\n"
            << "settling time (1 g step, " << lf.settling_band * 100 << " %): " << settling_text(lf)
            << "\novershoot: " << lf.overshoot * 100 << " %\nDC gain: " << lf.dc_gain << "\n";
  std::vector<std::string> notes;
  if (const std::string n = a.filter == "paper" ? paper_rate_note(p.loop.loop_rate_hz) : ""; !n.empty()) {
    std::cout << "note: " << n << "\n";
    notes.push_back(n);
  }
  // A --dut file's own [filter] is not the one shown (its custom sections printed "filter paper"
  // without a word: a metrologist's review); --filter names the filter shown.
  if (dc.own_filter) {
    const std::string n = shown_text(a.dut_file) + "'s [filter] is not the filter shown: --filter names it (" +
                          a.filter + " here)";
    std::cout << "note: " << n << "\n";
    notes.push_back(n);
  }
  // How to apply it: a technician could not use the filter `select` ranks first, as neither a
  // profile nor `rig dut set-filter` takes the name butterN@FC (a review). Every digit, so the
  // DUT gets the sections shown: the shortest text that reads back to each (17 digits printed the
  // paper's 0.377156 as 0.37715599999999999, a review).
  const auto num = [](double v) { return fmt::format("{}", v); };
  std::string toml_sections, biquads;
  nlohmann::json sections = nlohmann::json::array();
  for (const Biquad& b : f.sections) {
    const std::vector<std::string> v{num(b.b0), num(b.b1), num(b.b2), num(b.a1), num(b.a2)};
    toml_sections += (toml_sections.empty() ? "" : ", ") + fmt::format("[{}]", fmt::join(v, ", "));
    biquads += fmt::format(" --biquad {}", fmt::join(v, ","));
    sections.push_back({b.b0, b.b1, b.b2, b.a1, b.a2});
  }
  if (!f.sections.empty())
    std::cout << "\nto use it in a profile:\n[filter]\npreset = \"custom\"\nsections = [" << toml_sections
              << "]\nrate_hz = " << num(f.rate_hz) << "\nenabled = " << (f.enabled ? "true" : "false")
              << "\n\nto load it into a DUT by hand (IFACE: the DUT's CAN interface; or --hardware FILE):\n"
              << "rig dut --can IFACE set-filter" << biquads << " --rate " << num(f.rate_hz) << (f.enabled ? "" : " --off")
              << "\n";
  else  // "none": the filter off, which is a preset and a command of its own (a re-test found no block)
    std::cout << "\nto use it in a profile:\n[filter]\npreset = \"none\"\n\nto switch a DUT's filter off by hand (IFACE: the "
                 "DUT's CAN interface; or --hardware FILE):\nrig dut --can IFACE filter-off\n";
  if (!a.json_out.empty()) {
    json j = {{"filter", a.filter},
              {"source", "model"},
              {"bandwidth_0p5_hz", lf.bandwidth_0p5_hz},
              {"bandwidth_3db_hz", lf.bandwidth_3db_hz},
              {"settling_time_s", number_if(lf.settled, lf.settling_time_s)},
              {"settled", lf.settled},
              {"settling_time_at_least_s", number_if(!lf.settled, lf.settling_time_s)},
              {"step_window_s", lf.step_window_s},
              {"settling_band", lf.settling_band},
              {"overshoot", lf.overshoot},
              {"dc_gain", lf.dc_gain},
              {"sections", sections},  // [b0, b1, b2, a1, a2] each, H = (b0 + b1/z + b2/z^2)/(1 + a1/z + a2/z^2)
              {"rate_hz", f.rate_hz},
              {"enabled", f.enabled},
              {"notes", notes},
              {"step", {{"t_s", lf.step_t_s}, {"x", lf.step_x}, {"y", lf.step_y}}},
              {"response", {{"f_hz", lf.freq_hz}, {"amp_x", lf.amp_x}, {"amp_y", lf.amp_y}}}};
    write_json(a.json_out, j, "rig filter show --json");
  }
}

}  // namespace

void add_filter(CLI::App& app, int& rc) {
  auto* sub = app.add_subcommand("filter", "Output filter W_f(z): closed-loop figures and model-based selection");
  sub->require_subcommand(1);

  auto sa = std::make_shared<SelectArgs>();
  auto* sel = sub->add_subcommand("select", "Rank candidate filters by the paper's two criteria");
  // Every number has its range, checked on the text before any work (README, `rig filter`): a
  // negative or NaN --seconds was an allocation failure reported as exit 4, and 0 or inf ranked
  // every candidate on an RMS of 0 (a review). The cut-offs' range is checked as a whole by
  // select_filters (0 < min <= max, finite; at most 10000 cut-offs), before any work too.
  sel->add_option("--f-req", sa->f_req, "Required bandwidth at the 0.5 level, Hz, in (0, 1e6]")
      ->capture_default_str()
      ->check(number_in(0, 1e6, true, "a bandwidth in Hz"));
  sel->add_option("--tolerance", sa->tol, "Allowed bandwidth deviation, %, in (0, 100]")
      ->capture_default_str()
      ->check(number_in(0, 100, true, "a percentage"));
  // "1,2" as the help shows the default, or "1 2" (it refused the comma form and blamed a leading
  // zero, a review). Split here, not by CLI11's delimiter, which dropped an empty item ("1,,2",
  // "1,") without a word (a review).
  sel->add_option("--orders", sa->orders_text, "Butterworth orders to try, each 1 to 4, once (1,2 or 1 2; default 1,2,3,4)")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            for (const std::string& item : order_items(v)) {
              if (item.empty()) return "'" + shown_ascii(v) + "': an empty item in the list of orders (1,2 or 1 2)";
              // "1 2" quoted as one word: the blank is no separator here (a re-test: the message
              // offered "1 2" and refused it).
              if (item.find_first_of(" \t") != std::string::npos)
                return "'" + shown_ascii(v) + "': the orders as 1,2 or as separate words (--orders 1 2), not one word "
                       "with a blank";
              if (!whole_number(item, 1, 4))
                return "'" + shown_ascii(item) + "': must be a Butterworth order in [1, 4] (decimal, no sign, no leading zero)";
            }
            return {};
          },
          ""));
  // Finite as typed: 1e309 was named "inf" by the range check below (a review).
  sel->add_option("--fc-min", sa->fc_min, "Lowest cut-off, Hz (0 < min <= max)")
      ->capture_default_str()
      ->check(finite("a finite number of Hz"));
  sel->add_option("--fc-max", sa->fc_max, "Highest cut-off, Hz (finite)")
      ->capture_default_str()
      ->check(finite("a finite number of Hz"));
  sel->add_option("--fc-step", sa->fc_step, "Cut-off step, Hz (> 0; at most 10000 cut-offs)")
      ->capture_default_str()
      ->check(finite("a finite number of Hz"));
  sel->add_option("--seconds", sa->seconds, "Emulated output per candidate for the RMS, s, in (0, 3600]")
      ->capture_default_str()
      ->check(number_in(0, kMaxSelectSeconds, true, "a number of seconds"));
  sel->add_option("--seed", sa->seed, "Noise seed of the emulated DUT, a whole number >= 0")->capture_default_str();
  sel->add_option("--dut", sa->dut_file, "Profile or DUT TOML ([plant.dut] overrides)")->check(existing_file());
  sel->add_option("--recorded", sa->recorded,
                  "Criterion 1 on a recording of x at the DUT's loop rate (text, one value per line)")
      ->check(existing_file());
  sel->add_option("--top", sa->top, "Rows to print, >= 1")->capture_default_str()->check(whole_in("a number of rows", 1));
  sel->add_option("--json", sa->json_out, "Write every candidate as JSON");
  sel->callback([sa, &rc] {
    run_select(*sa);
    rc = kExitPass;
  });

  auto sh = std::make_shared<ShowArgs>();
  auto* show = sub->add_subcommand("show", "Closed-loop figures and curves with one filter");
  show->add_option("--filter", sh->filter, "paper | none | butterN@FC (e.g. butter2@500)")->capture_default_str();
  show->add_option("--dut", sh->dut_file, "Profile or DUT TOML ([plant.dut] overrides)")->check(existing_file());
  show->add_option("--json", sh->json_out, "Write figures, step and frequency response as JSON");
  show->callback([sh, &rc] {
    run_show(*sh);
    rc = kExitPass;
  });
}

}  // namespace rig::cli
