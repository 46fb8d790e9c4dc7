#include "procedures/acceptance/profile.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "analysis/allan.hpp"
#include "analysis/psd.hpp"
#include "design/filter.hpp"
#include "design/filter_toml.hpp"
#include "rig/core/escape.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/core/path_kind.hpp"

namespace rig::acceptance {

const std::map<std::string, std::string>& builtin_profiles();  // generated from profiles/*.toml

namespace {

// [profile] name: it names the passport, JUnit's suite, the history's rows and the default run
// folder, and the terminal shows it. "" gave a run folder runs/_-<time> and a passport of no
// profile; an escape sequence in it was sent to the terminal as it was (a review).
std::string read_profile_name(const toml::table& prof) {
  const std::string name = cfg::get_string(prof, "name");
  const toml::node& n = *prof.get("name");
  if (name.empty()) throw ConfigError(cfg::where(n) + ": 'name' = \"\": the profile's name is required, not empty");
  // Blanks only, or at an end: a name that reads as none on the passport and in the history's
  // listing, and a run folder runs/ -<time> (a review: " " was taken).
  if (name.find_first_not_of(" \t") == std::string::npos || name.front() == ' ' || name.back() == ' ' ||
      name.front() == '\t' || name.back() == '\t')
    throw ConfigError(cfg::where(n) + ": 'name' = \"" + shown_text(name) +
                      "\": the profile's name cannot begin or end with a blank");
  if (has_unshowable(name))
    throw ConfigError(cfg::where(n) + ": 'name' = \"" + shown_text(name) +
                      "\": a control character (shown here as \\xNN) cannot be in the profile's name");
  return name;
}

Orientation parse_orientation(const toml::table& t, std::string_view key, Orientation def) {
  const std::string s = cfg::get_string(t, key, std::string(to_string(def)));
  if (s == "U10") return Orientation::U10;
  if (s == "U20") return Orientation::U20;
  throw ConfigError(cfg::where(*t.get(key)) + ": '" + std::string(key) + "' must be \"U10\" or \"U20\", not \"" + s + "\"");
}

std::string digest(const toml::table& t) {
  std::ostringstream os;
  os << t;
  return std::to_string(std::hash<std::string>{}(os.str()));
}

// Every whole number as a float, for comparing two profiles by what they say: `run_s = 100` is the
// built-in's `run_s = 100.0` (a review: refused as a profile that differs from it).
void whole_numbers_as_floats(toml::table& t);
void whole_numbers_as_floats(toml::array& a) {
  for (std::size_t i = 0; i < a.size(); ++i) {
    toml::node& e = *a.get(i);
    if (const auto* v = e.as_integer()) a.replace(a.cbegin() + static_cast<std::ptrdiff_t>(i), static_cast<double>(v->get()));
    else if (auto* sub = e.as_table()) whole_numbers_as_floats(*sub);
    else if (auto* arr = e.as_array()) whole_numbers_as_floats(*arr);
  }
}
void whole_numbers_as_floats(toml::table& t) {
  std::vector<std::pair<std::string, double>> whole;
  for (auto&& [k, v] : t) {
    if (const auto* i = v.as_integer()) whole.emplace_back(std::string(k.str()), static_cast<double>(i->get()));
    else if (auto* sub = v.as_table()) whole_numbers_as_floats(*sub);
    else if (auto* arr = v.as_array()) whole_numbers_as_floats(*arr);
  }
  for (const auto& [k, x] : whole) t.insert_or_assign(k, x);
}

// The name the log and the passport give the profile's filter.
std::string filter_name(const std::string& preset) { return preset == "paper" ? "paper W_f(z)" : preset; }

}  // namespace

double Profile::planned_total_s() const {
  return static_cast<double>(order.size()) * (run_s + settle_s) + settle_s + in_run_s + settle_s + raw_s;
}

std::string gost_value_name(double block_s) { return fmt::format("in_run_b_gost_{:g}s", block_s); }

// The base's GOST B limits are named by the base's block lengths. A file that sets its own
// in_run_blocks_s keeps the base's limits only for the lengths it still has: a limit for a block
// the file no longer measures is the base's, not the user's, and would otherwise be refused as
// "unknown measurement", leaving no way to change the blocks but copying the whole profile.
std::vector<std::string> drop_limits_of_other_blocks(const toml::table& file, toml::table& base) {
  const toml::array* blocks = file["procedure"]["in_run_blocks_s"].as_array();
  toml::table* limits = base["limits"].as_table();
  if (!blocks || !limits) return {};  // (a malformed list is named when the profile is read)
  std::vector<std::string> kept, drop;
  for (const auto& b : *blocks)
    if (const auto v = b.value<double>()) kept.push_back(gost_value_name(*v));
  for (auto&& [k, v] : *limits)
    if (k.str().rfind("in_run_b_gost_", 0) == 0 && std::find(kept.begin(), kept.end(), k.str()) == kept.end())
      drop.emplace_back(k.str());
  for (const auto& k : drop) limits->erase(k);
  return drop;
}

void check_orientation_angles(const toml::table& t, double u10_deg, double u20_deg) {
  constexpr double kTolDeg = 10.0;
  const double apart = std::fmod(std::fabs(u20_deg - u10_deg), 360.0);
  if (std::fabs(apart - 180.0) <= kTolDeg) return;
  // Name the angle the user's file wrote: one merged in from a base profile has no place. Either
  // may be the wrong one: the other's place is said too (a mutated u10_deg was named only at u20's line).
  auto placed = [](const toml::node* n) { return n && n->source().path && n->source().begin.line > 0; };
  const toml::node* u10 = t.get("u10_deg");
  const std::string u10_at = placed(u10) && placed(t.get("u20_deg")) ? " (" + cfg::where(*u10) + ")" : "";
  const std::string why = fmt::format("U20 is {:g}° from u10_deg = {:g}°{}; the method turns the DUT 180° (± {:g}°) "
                                      "between U10 and U20",
                                      apart, u10_deg, u10_at, kTolDeg);
  if (const toml::node* n = t.get("u20_deg"); placed(n)) cfg::reject(*n, "u20_deg", why);
  if (const toml::node* n = t.get("u10_deg"); placed(n)) cfg::reject(*n, "u10_deg", why);
  throw ConfigError(cfg::where(t) + ": u20_deg = " + fmt::format("{:g}", u20_deg) + ": " + why);
}

uint64_t planned_samples(const Profile& p, double seconds) { return static_cast<uint64_t>(seconds * p.rate_hz + 0.5); }

std::vector<std::string> builtin_profile_names() {
  std::vector<std::string> n;
  for (const auto& [k, v] : builtin_profiles()) n.push_back(k);
  return n;
}

const std::string& builtin_profile_text(const std::string& name) {
  auto it = builtin_profiles().find(name);
  if (it == builtin_profiles().end()) throw ConfigError("no built-in profile '" + name + "'");
  return it->second;
}

namespace {
Profile parse_profile_table(const toml::table& t, const std::string& source) {
  // [plant] is the emulated plant's (it checks it itself): allowed here, never read.
  cfg::check_keys(t, {"base", "profile", "procedure", "table", "filter", "loop", "analysis", "limits", "classes", "plant"},
                  "top level");
  Profile p;
  p.source = source;
  p.digest = digest(t);
  const toml::table* prof = cfg::get_table(t, "profile", true);
  cfg::check_keys(*prof, {"name", "description"}, "profile");
  p.name = read_profile_name(*prof);
  p.description = cfg::get_string(*prof, "description", std::string());

  const toml::table* pr = cfg::get_table(t, "procedure", true);
  cfg::check_keys(*pr, {"rate_hz", "order", "run_s", "settle_s", "in_run_s", "in_run_orientation", "in_run_blocks_s",
                        "raw_s", "raw_orientation", "max_lost_samples", "retries"},
                  "procedure");
  p.rate_hz = cfg::get_number(*pr, "rate_hz", 1000.0, 1.0, 1e6);
  for (const std::string& o : cfg::get_strings(*pr, "order")) {
    if (o != "U10" && o != "U20")
      throw ConfigError(cfg::where(*pr->get("order")) + ": 'order' entries must be \"U10\" or \"U20\", not \"" + o + "\"");
    p.order.push_back(o == "U10" ? Orientation::U10 : Orientation::U20);
  }
  std::size_t n10 = 0;
  for (auto o : p.order) n10 += o == Orientation::U10;
  if (n10 == 0 || 2 * n10 != p.order.size())
    throw ConfigError(cfg::where(*pr->get("order")) +
                      ": 'order' needs as many U10 runs as U20 runs, at least one each (formulas (3), (4) pair them)");
  const double min_s = 2.0 / p.rate_hz;
  p.run_s = cfg::get_number(*pr, "run_s", std::nullopt, min_s, 1e6);
  p.settle_s = cfg::get_number(*pr, "settle_s", 10.0, 0.0, 1e5);
  p.in_run_s = cfg::get_number(*pr, "in_run_s", std::nullopt, min_s, 1e7);
  p.in_run_orientation = parse_orientation(*pr, "in_run_orientation", Orientation::U10);
  p.in_run_blocks_s = cfg::get_numbers(*pr, "in_run_blocks_s", std::vector<double>{100, 200});
  // Each block length is a whole number of samples to 1 % (GOST R 8.736's blocks are means of
  // samples: a length of 1.5 samples, or under one, has no such means), at least 2 blocks fit in the
  // in-run record, and no two lengths share a value name (both would be in_run_b_gost_2s).
  // Checked here, before any device opens: it used to surface after the in-run recording.
  const auto bad_blocks = [&](const std::string& why) {
    if (const toml::node* n = pr->get("in_run_blocks_s")) cfg::reject(*n, "in_run_blocks_s", why);
    throw ConfigError(cfg::where(*pr) + ": " + why);
  };
  if (p.in_run_blocks_s.empty()) bad_blocks("give at least one block length (the first is B's, GOST R 8.736)");
  for (std::size_t i = 0; i < p.in_run_blocks_s.size(); ++i) {
    const double b = p.in_run_blocks_s[i], samples = b * p.rate_hz;
    if (!(b > 0) || 2 * b > p.in_run_s)
      bad_blocks(fmt::format("{} s: each block length must be > 0 and give at least 2 blocks in in_run_s = {:g}", b,
                             p.in_run_s));
    // The in-run phase rounds the length to samples; a rounding of more than 1 % (1.5 samples
    // read as 2) would report a B of blocks other than the profile's.
    const double rounded = static_cast<double>(planned_samples(p, b));  // as the in-run phase reads it
    if (!(rounded >= 1) || std::abs(samples - rounded) > 0.01 * samples)
      bad_blocks(fmt::format("{} s: a block must be a whole number of samples (within 1 %) at rate_hz = {:g} "
                             "({:.10g} samples)",
                             b, p.rate_hz, samples));
    for (std::size_t j = 0; j < i; ++j)
      if (gost_value_name(p.in_run_blocks_s[j]) == gost_value_name(b))
        bad_blocks(fmt::format("{} s and {} s: both would be measured as {}", p.in_run_blocks_s[j], b,
                               gost_value_name(b)));
  }
  p.raw_s = cfg::get_number(*pr, "raw_s", std::nullopt, min_s, 1e7);
  // The raw capture's PSD (Welch) needs one segment: a shorter one was refused by the analysis
  // after the whole procedure, as a hardware fault (exit 4) on every resume alike (a review).
  if (const std::uint64_t n = planned_samples(p, p.raw_s); n < analysis::welch_segment(n, {}))
    throw ConfigError(cfg::where(*pr->get("raw_s")) + fmt::format(": 'raw_s' = {:g}: the raw capture must hold at least "
                                                                  "{} samples at rate_hz = {:g} (one segment of its "
                                                                  "PSD), {:g} s; this gives {}",
                                                                  p.raw_s, analysis::welch_segment(n, {}), p.rate_hz,
                                                                  static_cast<double>(analysis::welch_segment(n, {})) / p.rate_hz, n));
  p.raw_orientation = parse_orientation(*pr, "raw_orientation", Orientation::U10);
  p.max_lost_samples = static_cast<uint64_t>(cfg::get_int(*pr, "max_lost_samples", 0, 0));
  p.retries = static_cast<int>(cfg::get_int(*pr, "retries", 0, 0, 10));

  if (const toml::table* tb = cfg::get_table(t, "table")) {
    cfg::check_keys(*tb, {"u10_deg", "u20_deg"}, "table");
    p.u10_deg = cfg::get_number(*tb, "u10_deg", 0.0, -360.0, 360.0);
    p.u20_deg = cfg::get_number(*tb, "u20_deg", p.u10_deg + 180.0, -360.0, 540.0);
    check_orientation_angles(*tb, p.u10_deg, p.u20_deg);
  }
  p.filter = design::paper_wf();  // without a [filter] table
  std::string preset = "paper";
  if (const toml::table* f = cfg::get_table(t, "filter")) {
    const std::string read = design::read_filter_table(*f, "filter", design::RateKey::allowed, p.filter);
    if (!read.empty()) preset = read;
  }
  p.filter_name = filter_name(preset);
  if (const toml::table* l = cfg::get_table(t, "loop")) {
    cfg::check_keys(*l, {"amplitude_g", "steps", "record_ms"}, "loop");
    // The protocol's bounds (docs/can-protocol.md, LOOP_TEST): |A| <= 5 g, 10..200 ms.
    p.loop_amplitude_g = cfg::get_number(*l, "amplitude_g", p.loop_amplitude_g, -5.0, 5.0);
    if (p.loop_amplitude_g == 0) throw ConfigError(cfg::where(*l->get("amplitude_g")) + ": [loop] amplitude_g must not be 0");
    p.loop_steps = static_cast<int>(cfg::get_int(*l, "steps", p.loop_steps, 1, 100));
    p.loop_record_s = static_cast<double>(cfg::get_int(*l, "record_ms", 100, 10, 200)) / 1e3;
  }
  if (const toml::table* a = cfg::get_table(t, "analysis")) {
    cfg::check_keys(*a, {"taus", "confidence", "r_min_record_s", "b_allan"}, "analysis");
    p.taus = cfg::get_string(*a, "taus", p.taus);
    // Checked here, not first in the allan phase after the whole recording (issue 13).
    if (const toml::node* n = a->get("taus")) {
      analysis::TauGrid grid;
      try {
        grid = analysis::parse_tau_grid(p.taus);
      } catch (const std::invalid_argument& e) {
        cfg::reject(*n, "taus", e.what());
      }
      // "all" on the raw capture's two channels is refused where `rig analyze --taus all` would
      // refuse it: a review's 200-s capture spent 26 s in the allan phase, the paper's hour
      // would spend hours there, after the whole procedure.
      if (grid.kind == analysis::TauGrid::All) {
        const std::uint64_t n_phase = planned_samples(p, p.raw_s) + 1;
        const double per_value = static_cast<double>(analysis::max_factor(analysis::Deviation::OADEV, n_phase)) /
                                 static_cast<double>(n_phase);
        const double work = 2 * per_value * static_cast<double>(n_phase) * static_cast<double>(n_phase);
        if (work > analysis::kAllTermSums)
          cfg::reject(*n, "taus",
                      fmt::format("\"all\" on the raw capture's {} samples asks for every averaging factor ({:.2g} "
                                  "term sums over its two channels, more than the {:.2g} rig analyze runs): give "
                                  "\"log:N\" (log:100000 the finest) or \"octave\", or \"all\" with raw_s of at "
                                  "most {:g} s at rate_hz = {:g}",
                                  n_phase - 1, work, analysis::kAllTermSums,
                                  std::floor(std::sqrt(analysis::kAllTermSums / (2 * per_value))) / p.rate_hz,
                                  p.rate_hz));
      }
    }
    p.confidence = cfg::get_number(*a, "confidence", p.confidence, 0.01, 0.9999);
    p.r_min_record_s = cfg::get_number(*a, "r_min_record_s", p.r_min_record_s, 0.0);
    p.b_allan = cfg::get_string(*a, "b_allan", p.b_allan);
    if (p.b_allan != "paper" && p.b_allan != "lsq")
      cfg::reject(*a->get("b_allan"), "b_allan", "must be \"paper\" or \"lsq\"");
  }
  // The measurement names (docs/profiles.md); GOST B is named by its block length.
  std::vector<std::string> known = {"bias", "base_error", "in_run_b_allan", "tau_cp", "q", "n", "k", "r",
                                    "in_run_b_allan_filtered", "rms_unfiltered", "rms_filtered", "bandwidth_0p5",
                                    "settling_time", "accuracy_class"};
  std::string gost_names;
  for (double b : p.in_run_blocks_s) {
    known.push_back(gost_value_name(b));
    gost_names += (gost_names.empty() ? "" : ", ") + known.back();
  }
  if (const toml::table* l = cfg::get_table(t, "limits")) {
    for (auto&& [k, v] : *l) {
      bool ok = false;
      for (const auto& n : known) ok = ok || k.str() == n;
      if (!ok && k.str().rfind("in_run_b_gost_", 0) == 0)
        throw ConfigError(cfg::where(v) + ": unknown measurement '" + std::string(k.str()) +
                          "' in [limits]: GOST B is named by its block length, and in_run_blocks_s gives " + gost_names);
      if (!ok) {  // the names, as the hardware file's unknown keys are listed (a technician's review)
        std::string names;
        for (const auto& n : known) names += (names.empty() ? "" : ", ") + n;
        throw ConfigError(cfg::where(v) + ": unknown measurement '" + std::string(k.str()) + "' in [limits] (known: " +
                          names + ")");
      }
      const std::vector<double> mm = cfg::get_numbers(*l, k.str());
      if (mm.size() != 2) cfg::reject(v, k.str(), "limits are two numbers [min, max], got " + std::to_string(mm.size()));
      if (mm[0] > mm[1]) cfg::reject(v, k.str(), "limits must be [min, max] with min <= max");
      p.limits[std::string(k.str())] = {mm[0], mm[1]};
    }
  }
  if (const toml::node* cn = t.get("classes")) {
    const toml::array* arr = cn->as_array();
    if (!arr) throw ConfigError(cfg::where(*cn) + ": 'classes' must be an array of tables ([[classes]])");
    for (const toml::node& c : *arr) {
      const toml::table* ct = c.as_table();
      if (!ct) throw ConfigError(cfg::where(c) + ": each [[classes]] entry must be a table");
      cfg::check_keys(*ct, {"name", "max_b_g"}, "classes");
      AccuracyClass ac{cfg::get_string(*ct, "name"), cfg::get_number(*ct, "max_b_g", std::nullopt, 0.0)};
      // The passport names the class: an empty name, or one two classes share, says nothing of
      // which it is (a review: accuracy_class 2, "precision", with "precision" twice).
      const bool blank = ac.name.find_first_not_of(" \t") == std::string::npos;
      const bool taken = std::any_of(p.classes.begin(), p.classes.end(),
                                     [&](const AccuracyClass& o) { return o.name == ac.name; });
      if (blank || taken)
        cfg::reject(*ct->get("name"), "name", blank ? "a class needs a name" : "another [[classes]] entry has that name");
      if (!p.classes.empty() && ac.max_b_g <= p.classes.back().max_b_g)
        throw ConfigError(cfg::where(*ct->get("max_b_g")) + ": 'max_b_g' = " + fmt::format("{:g}", ac.max_b_g) +
                          ": [[classes]] must be in ascending max_b_g (the class before has " +
                          fmt::format("{:g}", p.classes.back().max_b_g) + ")");
      p.classes.push_back(ac);
    }
  }
  // A limited class with no class to read is never measured, so every run would end FAIL after
  // the whole procedure (a review: a 2-hour run failing every DUT; the dry run said nothing).
  if (p.classes.empty() && p.limits.count("accuracy_class"))
    throw ConfigError(cfg::where(*cfg::get_table(t, "limits")->get("accuracy_class")) +
                      ": [limits] accuracy_class is limited, but the profile has no accuracy classes ([[classes]]): "
                      "it could never be measured and every run would FAIL; give [[classes]] or remove the limit");
  return p;
}

}  // namespace

Profile parse_profile(const toml::table& t, const std::string& source) {
  try {
    return parse_profile_table(t, source);
  } catch (const ConfigError& e) {
    // A value the file inherits is named at the base's line, which the user cannot edit: say
    // which file inherited it, where a key of its own would change it.
    const std::string what = e.what();
    if (source.rfind("builtin:", 0) != 0 && what.rfind("builtin:", 0) == 0)
      throw ConfigError(what + " (inherited by " + shown_text(source) + " from its base; set the key there to change it)");
    throw;
  }
}

Profile load_profile(const std::string& name_or_path) {
  std::string source;
  const toml::table t = load_profile_table(name_or_path, source);
  return parse_profile(t, source);
}

// A file's profile names itself: one built on a base without a [profile] name of its own took
// the base's, and a run with the limits loosened 1000x was passported, JUnit-suited and recorded
// in the history as the built-in "ci" (an outside review). A file may carry a built-in's name only
// while it is that profile, key for key but its [plant].
void check_profile_names_itself(const toml::table& resolved, const std::string& source) {
  if (source.rfind("builtin:", 0) == 0) return;
  const toml::table file = cfg::parse_file(source);
  const toml::node* own = file.at_path("profile.name").node();
  const toml::node* base = file.get("base");
  const auto name = resolved.at_path("profile.name").value<std::string>();
  if (!name) return;  // (a missing name is parse_profile's to say)
  // [plant] is the emulated plant's (a seed, a table's speed), not the procedure's or its limits.
  auto procedure = [](toml::table t) {
    t.erase("plant");
    whole_numbers_as_floats(t);
    return digest(t);
  };
  const auto it = builtin_profiles().find(*name);
  if (it != builtin_profiles().end() && procedure(resolved) == procedure(cfg::parse_string(it->second, "builtin:" + *name)))
    return;  // that built-in, key for key
  if (!own) {
    if (base)
      throw ConfigError(cfg::where(*base) + ": 'base' = \"" + shown_text(base->value_or(std::string())) +
                        "\": a profile built on another needs a name of its own: add [profile] name = \"...\" to " +
                        shown_text(source) + " (without one its passport, JUnit suite and history rows would say \"" +
                        shown_text(*name) + "\")");
    return;
  }
  if (it == builtin_profiles().end()) return;
  throw ConfigError(cfg::where(*own) + ": 'name' = \"" + shown_text(*name) +
                    "\": the built-in profile's name, on a profile that differs from it: give it a name of its own "
                    "(its passport, JUnit suite and history rows would say it is the built-in)");
}

toml::table load_profile_table(const std::string& name_or_path, std::string& source,
                               std::vector<std::string>* dropped_limits) {
  const auto& builtin = builtin_profiles();
  toml::table t;
  if (auto it = builtin.find(name_or_path); it != builtin.end()) {
    t = cfg::parse_string(it->second, "builtin:" + name_or_path);
    source = "builtin:" + name_or_path;
  } else {
    if (path_kind(name_or_path, "profile") == PathKind::missing) {
      std::string names;
      for (const auto& [k, v] : builtin) names += (names.empty() ? "" : ", ") + k;
      throw ConfigError("profile '" + shown_text(name_or_path) + "': no such file and not a built-in profile (" + names +
                        ")");
    }
    source = name_or_path;
    t = resolve_profile_file(cfg::parse_file(name_or_path), dropped_limits);
  }
  return t;
}

toml::table resolve_profile_file(toml::table t, std::vector<std::string>* dropped_limits) {
  const auto& builtin = builtin_profiles();
  if (const toml::node* b = t.get("base")) {
    const auto base_name = b->value<std::string>();
    auto bit = base_name ? builtin.find(*base_name) : builtin.end();
    if (bit == builtin.end()) {
      std::string names;
      for (const auto& [k, v] : builtin) names += (names.empty() ? "" : ", ") + k;
      cfg::reject(*b, "base", "must name a built-in profile (" + names + ")");
    }
    toml::table base = cfg::parse_string(bit->second, "builtin:" + *base_name);
    t.erase("base");
    // A file's own [[classes]] replace the base's rather than append.
    if (t.contains("classes")) base.erase("classes");
    const std::vector<std::string> dropped = drop_limits_of_other_blocks(t, base);
    if (dropped_limits) *dropped_limits = dropped;
    cfg::fill_defaults(t, std::move(base));
  }
  // `bias = []` in [limits]: that value reported, not judged. A file built on a base could
  // loosen an inherited limit but never remove one (an integrator's review: a whole profile of
  // its own was the only way).
  if (toml::table* lim = t.get_as<toml::table>("limits")) {
    std::vector<std::string> unlimited;
    for (auto&& [k, v] : *lim)
      if (const toml::array* a = v.as_array(); a && a->empty()) unlimited.emplace_back(k.str());
    for (const std::string& k : unlimited) lim->erase(k);
  }
  return t;
}

std::string unjudged_blocks_note(const Profile& p, const std::vector<std::string>& dropped_limits) {
  std::string unjudged, dropped;
  // The values every built-in profile judges, and the profile's own GOST blocks: one left without
  // limits (`bandwidth_0p5 = []`, or its line deleted from a copy) passed unseen (a review).
  for (const char* v : {"bias", "base_error", "rms_filtered", "bandwidth_0p5", "settling_time"})
    if (!p.limits.count(v)) unjudged += (unjudged.empty() ? "" : ", ") + std::string(v);
  for (const double b : p.in_run_blocks_s)
    if (!p.limits.count(gost_value_name(b))) unjudged += (unjudged.empty() ? "" : ", ") + gost_value_name(b);
  if (unjudged.empty()) return "";
  for (const auto& d : dropped_limits) dropped += (dropped.empty() ? "" : ", ") + d;
  return fmt::format("{}: {}{} {} no limits: UNSET in the passport, never FAIL (give them in [limits] to judge them)",
                     p.source,
                     dropped.empty() ? "" : "its own in_run_blocks_s leaves out its base's limits (" + dropped + "); ",
                     unjudged, unjudged.find(',') == std::string::npos ? "has" : "have");
}

}  // namespace rig::acceptance
