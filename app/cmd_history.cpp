// `rig history`: lists recorded runs, or trends one measurement across DUTs or across the
// runs of one DUT; also records a run folder into the database (--record).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "app/commands.hpp"
#include "app/history_source.hpp"
#include "app/whole_number.hpp"
#include "rig/core/errors.hpp"
#include "rig/report/db.hpp"
#include "rig/report/history.hpp"
#include "rig/report/passport_check.hpp"
#include "rig/core/path_kind.hpp"

namespace rig::cli {

namespace {

// A mistake of the passport or of an option, not of the database: never "RIG_HISTORY: ...".
struct NotTheDatabase : ConfigError {
  using ConfigError::ConfigError;
};

struct HistoryArgs {
  std::string db;
  std::string serial, since, until, outcome, profile, value, record;
  int limit = 0;
  bool csv = false;
};

std::optional<std::string> opt(const std::string& s) { return s.empty() ? std::nullopt : std::optional(s); }

// RFC 4180 field.
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string full(const std::optional<double>& v) {  // CSV: every digit
  if (!v) return "";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", *v);
  return buf;
}
std::string brief(const std::optional<double>& v) {  // tables: people
  if (!v) return "-";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", *v);
  return buf;
}

// Left-aligned text columns.
void print_table(std::ostream& os, const std::vector<std::vector<std::string>>& rows) {
  std::vector<std::size_t> w;
  for (const auto& r : rows)
    for (std::size_t i = 0; i < r.size(); ++i) {
      if (w.size() <= i) w.push_back(0);
      w[i] = std::max(w[i], r[i].size());
    }
  for (const auto& r : rows) {
    std::string line;
    for (std::size_t i = 0; i < r.size(); ++i) {
      line += r[i];
      if (i + 1 < r.size()) line += std::string(w[i] - r[i].size() + 2, ' ');
    }
    line.erase(line.find_last_not_of(' ') + 1);
    os << line << "\n";
  }
}

void list(const HistoryArgs& a, const history::Filter& f) {
  const auto runs = history::list_runs(a.db, f);
  std::vector<std::vector<std::string>> rows;
  rows.push_back({"id", "started", "serial", "profile", "plant", "outcome", "station", "software", "run_dir", "captures"});
  for (const auto& r : runs) {
    std::string caps;
    for (const auto& c : r.captures) caps += (caps.empty() ? "" : ";") + c;
    rows.push_back({std::to_string(r.id), r.started, r.serial, r.profile, r.plant, r.outcome, r.station, r.software,
                    r.run_dir, a.csv ? caps : std::to_string(r.captures.size())});
  }
  if (a.csv) {
    for (const auto& r : rows) {
      std::string line;
      for (std::size_t i = 0; i < r.size(); ++i) line += (i ? "," : "") + csv_field(r[i]);
      std::cout << line << "\r\n";
    }
    return;
  }
  if (runs.empty()) {
    std::cout << "no runs recorded" << (f.serial || f.since || f.until || f.outcome || f.profile ? " match" : "")
              << " (" << a.db << ")\n";
    return;
  }
  print_table(std::cout, rows);
}

struct Stats {
  std::size_t n = 0;
  double mean = 0, m2 = 0, min = INFINITY, max = -INFINITY, first = NAN, last = NAN;
  void add(double v) {  // Welford's running mean and variance
    ++n;
    const double d = v - mean;
    mean += d / static_cast<double>(n);
    m2 += d * (v - mean);
    min = std::min(min, v);
    max = std::max(max, v);
    if (n == 1) first = v;
    last = v;
  }
  double sd() const { return n > 1 ? std::sqrt(m2 / static_cast<double>(n - 1)) : NAN; }
};

void trend(const HistoryArgs& a, const history::Filter& f) {
  const auto rows = history::trend(a.db, a.value, f);
  if (rows.empty()) {
    const auto names = history::value_names(a.db);
    if (std::find(names.begin(), names.end(), a.value) == names.end()) {
      std::string known;
      for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
      throw NotTheDatabase("--value '" + a.value + "': no such measurement recorded in " + a.db +
                        (known.empty() ? std::string(" (the database holds no runs)") : " (recorded: " + known + ")"));
    }
  }
  if (a.csv) {
    std::cout << "run_id,started,serial,run_outcome,name,value,unit,lo,hi,limit_min,limit_max,outcome,reason\r\n";
    for (const auto& r : rows)
      std::cout << r.run_id << ',' << csv_field(r.started) << ',' << csv_field(r.serial) << ',' << csv_field(r.outcome)
                << ',' << csv_field(a.value) << ',' << full(r.value) << ',' << csv_field(r.unit) << ',' << full(r.lo)
                << ',' << full(r.hi) << ',' << full(r.limit_min) << ',' << full(r.limit_max) << ','
                << csv_field(r.value_outcome) << ',' << csv_field(r.reason) << "\r\n";
    return;
  }
  std::vector<std::vector<std::string>> t;
  t.push_back({"id", "started", "serial", "value", "unit", "lo", "hi", "limits", "outcome", "reason"});
  std::map<std::string, Stats> per_serial;
  Stats all;
  for (const auto& r : rows) {
    const std::string limits =
        r.limit_min || r.limit_max ? "[" + brief(r.limit_min) + ", " + brief(r.limit_max) + "]" : "-";
    t.push_back({std::to_string(r.run_id), r.started, r.serial, brief(r.value), r.unit, brief(r.lo), brief(r.hi), limits,
                 r.value_outcome, r.reason});
    if (r.value && std::isfinite(*r.value)) {
      per_serial[r.serial].add(*r.value);
      all.add(*r.value);
    }
  }
  std::cout << a.value << " over " << rows.size() << " run(s)\n";
  print_table(std::cout, t);
  // The trend: per DUT (across its runs) and across all DUTs.
  std::vector<std::vector<std::string>> s;
  s.push_back({"serial", "n", "mean", "sd", "min", "max", "last - first"});
  auto row = [&](const std::string& name, const Stats& st, bool one_dut) {
    s.push_back({name, std::to_string(st.n), brief(st.mean), brief(std::isnan(st.sd()) ? std::nullopt : std::optional(st.sd())),
                 brief(st.min), brief(st.max), one_dut ? brief(st.last - st.first) : "-"});
  };
  for (const auto& [serial, st] : per_serial) row(serial, st, true);
  if (per_serial.size() > 1) row("all DUTs", all, false);  // drift only means something within one DUT
  if (all.n) {
    std::cout << "\n";
    print_table(std::cout, s);
  }
}

void record(const HistoryArgs& a) {
  const std::string path = a.record + "/passport.json";
  std::ifstream in(path);
  if (!in) throw NotTheDatabase(path + ": cannot read the file");
  nlohmann::json p;
  try {
    p = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw NotTheDatabase(path + ": malformed JSON: " + e.what());
  }
  try {
    report::require_consistent_verdicts(p, path);  // an edited passport is not history
  } catch (const ConfigError& e) {
    throw NotTheDatabase(e.what());
  }
  const long long id = history::record_run(a.db, p, a.record);
  std::cout << "recorded run " << id << " (" << p.value("serial", "") << ", " << p.value("outcome", "") << ") in "
            << a.db << "\n";
}

int run_history(const HistoryArgs& a, bool db_given) {
  if (!a.record.empty()) {
    record(a);
    return kExitPass;
  }
  // Reading never creates a database. A --db that names no file is a mistake (exit 2, from
  // the reader); the default database merely does not exist until the first run records.
  if (const auto path = history::sqlite_path(a.db); !db_given && path && path_kind(*path, "history database") == PathKind::missing) {
    std::cout << "no runs recorded yet (" << a.db << " does not exist)\n";
    return kExitPass;
  }
  history::Filter f{opt(a.serial), opt(a.since), opt(a.until), opt(a.outcome), opt(a.profile), a.limit};
  if (a.value.empty()) list(a, f);
  else trend(a, f);
  return kExitPass;
}

}  // namespace

void add_history(CLI::App& app, int& rc) {
  auto* sub = app.add_subcommand("history", "List recorded runs or trend a measurement (results database)");
  auto a = std::make_shared<HistoryArgs>();
  sub->add_option("--db", a->db, "Database URL: sqlite:PATH, PATH or postgresql://... (default: $RIG_HISTORY, "
                                  "[history] url in the rig config, ~/.local/share/rig/history.sqlite)");
  sub->add_option("--serial", a->serial, "Only this DUT serial number");
  sub->add_option("--since", a->since, "Only runs started at or after this ISO 8601 date/time (UTC if no zone)");
  sub->add_option("--until", a->until, "Only runs started before this ISO 8601 date/time");
  sub->add_option("--outcome", a->outcome, "Only runs with this outcome")
      ->check(CLI::IsMember({"PASS", "FAIL", "ABORTED", "ERROR"}));
  sub->add_option("--profile", a->profile, "Only runs of this profile");
  sub->add_option("--value", a->value, "Trend this passport measurement (e.g. in_run_b_allan) instead of listing runs");
  // 0 would mean "no limit" to the query: a user who types --limit 0 asked for none, so N >= 1.
  sub->add_option("--limit", a->limit, "Only the newest N runs (N >= 1)")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            return whole_number(v, 1, std::numeric_limits<int>::max()) ? std::string()
                                                                       : v + ": must be a whole number in [1, 2147483647]";
          },
          "N >= 1"));
  sub->add_flag("--csv", a->csv, "Comma-separated output (RFC 4180) with every digit");
  sub->add_option("--record", a->record, "Record the run folder DIR (its passport.json) into the database, then exit");
  sub->callback([&rc, a] {
    const bool db_given = !a->db.empty();  // (an empty --db is refused as such by main.cpp)
    HistorySource source{a->db};
    if (!db_given) source = default_history();
    a->db = source.url;
    try {
      rc = run_history(*a, db_given);
    } catch (const NotTheDatabase&) {
      throw;  // the passport's or the option's own mistake, whichever database (a code review)
    } catch (const ConfigError& e) {
      // A database $RIG_HISTORY names is the environment's mistake: said so, or the user looks
      // for a --db that was never given (a review).
      if (!source.from_rig_history) throw;
      throw ConfigError(std::string("RIG_HISTORY: ") + e.what());
    }
  });
}

}  // namespace rig::cli
