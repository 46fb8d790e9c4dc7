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
#include <set>
#include <tuple>
#include <memory>
#include <optional>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "app/commands.hpp"
#include "rig/core/json_unique.hpp"
#include "app/folder_lock.hpp"
#include "app/history_source.hpp"
#include "app/passport_held.hpp"
#include "app/run_seal.hpp"
#include "app/number_option.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"
#include "rig/report/db.hpp"
#include "rig/report/db_url.hpp"
#include "rig/report/history.hpp"
#include "rig/report/passport_read.hpp"
#include "rig/report/timefmt.hpp"
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
  std::string seal_key;  // --seal-key / RIG_SEAL_KEY: a sealed folder is checked before --record takes it
  bool seal_key_given = false;
  int limit = 0;
  long long endings = 0;  // --endings ID
  bool csv = false;
  bool no_serial = false;  // only runs that stopped before the DUT said its serial (the option
                           // refuses an empty value, as every text option does)
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

// Characters a terminal shows for UTF-8 text: its code points (a serial "ДУТ-Ü7" is 6, not 11
// bytes; padding by bytes shifted every column after it, a review). Wide CJK forms are not
// measured.
std::size_t shown_width(const std::string& s) {
  return static_cast<std::size_t>(
      std::count_if(s.begin(), s.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

// Left-aligned text columns, each cell as a message shows a name (shown_text): a folder path's
// control characters went to the terminal raw (a review; the CSV quotes them as they are).
void print_table(std::ostream& os, std::vector<std::vector<std::string>> rows) {
  for (auto& r : rows)
    for (std::string& cell : r) cell = shown_text(cell);
  std::vector<std::size_t> w;
  for (const auto& r : rows)
    for (std::size_t i = 0; i < r.size(); ++i) {
      if (w.size() <= i) w.push_back(0);
      w[i] = std::max(w[i], shown_width(r[i]));
    }
  for (const auto& r : rows) {
    std::string line;
    for (std::size_t i = 0; i < r.size(); ++i) {
      line += r[i];
      if (i + 1 < r.size()) line += std::string(w[i] - shown_width(r[i]) + 2, ' ');
    }
    line.erase(line.find_last_not_of(' ') + 1);
    os << line << "\n";
  }
}

void list(const HistoryArgs& a, const history::Filter& f) {
  const auto runs = history::list_runs(a.db, f);
  std::vector<std::vector<std::string>> rows;
  rows.push_back(
      {"id", "started", "serial", "profile", "plant", "outcome", "station", "software", "run_dir", "captures", "earlier"});
  const auto joined = [](const std::vector<std::string>& v) {
    std::string out;
    for (const auto& x : v) out += (out.empty() ? "" : ";") + x;
    return out;
  };
  for (const auto& r : runs)
    rows.push_back({std::to_string(r.id), r.started, r.serial, r.profile, r.plant, r.outcome, r.station, r.software,
                    r.run_dir, a.csv ? joined(r.captures) : std::to_string(r.captures.size()), joined(r.earlier)});
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
  std::size_t runs = 0, n = 0;  // runs seen; values among them (a null value is a run without one)
  double mean = 0, m2 = 0, min = INFINITY, max = -INFINITY, first = NAN, last = NAN;
  void add(const std::optional<double>& value) {
    ++runs;
    if (value && std::isfinite(*value)) add(*value);
  }
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
    // `profile` last (added 2026-12-02): a reader of the columns before it reads them as before.
    std::cout << "run_id,started,serial,run_outcome,name,value,unit,lo,hi,limit_min,limit_max,outcome,reason,profile\r\n";
    for (const auto& r : rows)
      std::cout << r.run_id << ',' << csv_field(r.started) << ',' << csv_field(r.serial) << ',' << csv_field(r.outcome)
                << ',' << csv_field(a.value) << ',' << full(r.value) << ',' << csv_field(r.unit) << ',' << full(r.lo)
                << ',' << full(r.hi) << ',' << full(r.limit_min) << ',' << full(r.limit_max) << ','
                << csv_field(r.value_outcome) << ',' << csv_field(r.reason) << ',' << csv_field(r.profile) << "\r\n";
    return;
  }
  std::vector<std::vector<std::string>> t;
  t.push_back({"id", "started", "serial", "run", "value", "unit", "lo", "hi", "limits", "outcome", "reason", "profile"});
  // The statistics per DUT, unit and profile (a run that wrote the value in mg is not averaged
  // with one in g, a review; nor a ci run's with a paper run's: another procedure, other record
  // lengths, a technician's review); `runs` counts every run of the DUT, `n` those with a value.
  using Key = std::tuple<std::string, std::string, std::string>;  // serial, unit, profile
  std::map<Key, Stats> per_serial;
  std::map<std::pair<std::string, std::string>, Stats> all;  // by unit, profile
  for (const auto& r : rows) {
    const std::string limits =
        r.limit_min || r.limit_max ? "[" + brief(r.limit_min) + ", " + brief(r.limit_max) + "]" : "-";
    t.push_back({std::to_string(r.run_id), r.started, r.serial, r.outcome, brief(r.value), r.unit, brief(r.lo),
                 brief(r.hi), limits, r.value_outcome, r.reason, r.profile.empty() ? "-" : r.profile});
    const std::string profile = r.profile.empty() ? "-" : r.profile;  // a row from before profiles were kept
    per_serial[{r.serial, r.unit, profile}].add(r.value);
    all[{r.unit, profile}].add(r.value);
  }
  std::cout << a.value << " over " << rows.size() << " run(s)\n";
  print_table(std::cout, t);
  // The trend: per DUT (across its runs) and across all DUTs.
  std::vector<std::vector<std::string>> s;
  s.push_back({"serial", "unit", "profile", "runs", "n", "mean", "sd", "min", "max", "last - first"});
  auto row = [&](const std::string& name, const std::string& unit, const std::string& profile, const Stats& st,
                 bool one_dut) {
    const auto number = [&st](double v) { return st.n ? brief(v) : std::string("-"); };
    s.push_back({name, unit, profile, std::to_string(st.runs), std::to_string(st.n), number(st.mean),
                 brief(std::isnan(st.sd()) ? std::nullopt : std::optional(st.sd())), number(st.min), number(st.max),
                 one_dut ? number(st.last - st.first) : "-"});
  };
  for (const auto& [key, st] : per_serial) row(std::get<0>(key), std::get<1>(key), std::get<2>(key), st, true);
  std::set<std::string> units, profiles;
  for (const auto& entry : all) {  // drift only means something within one DUT
    const auto key = entry.first;  // not a structured binding: clang 14 cannot capture one
    units.insert(key.first);
    profiles.insert(key.second);
    const auto duts = std::count_if(per_serial.begin(), per_serial.end(), [&](const auto& e) {
      return std::get<1>(e.first) == key.first && std::get<2>(e.first) == key.second;
    });
    if (duts > 1) row("all DUTs", key.first, key.second, entry.second, false);
  }
  if (units.size() > 1)
    std::cout << "\nnote: " << a.value << " was recorded in " << units.size()
              << " units; each unit has its own statistics\n";
  if (profiles.size() > 1)
    std::cout << (units.size() > 1 ? "" : "\n") << "note: " << a.value << " was measured under " << profiles.size()
              << " profiles; each profile has its own statistics (--profile P for one)\n";
  if (!per_serial.empty()) {
    std::cout << "\n";
    print_table(std::cout, s);
  }
}

// The endings of one run, in the order recorded: a resume's, a folder put back and resumed.
void endings(const HistoryArgs& a) {
  const auto rows = history::endings_of(a.db, a.endings);
  if (rows.empty()) throw NotTheDatabase("--endings " + std::to_string(a.endings) + ": no such run in " + a.db);
  if (a.csv) {
    std::cout << "run_id,seq,recorded,finished,outcome,aborted_reason\r\n";
    for (const auto& e : rows)
      std::cout << a.endings << ',' << e.seq << ',' << csv_field(e.recorded) << ',' << csv_field(e.finished) << ','
                << csv_field(e.outcome) << ',' << csv_field(e.aborted_reason) << "\r\n";
    return;
  }
  std::vector<std::vector<std::string>> t;
  t.push_back({"seq", "recorded", "finished", "outcome", "aborted_reason"});
  for (const auto& e : rows) t.push_back({std::to_string(e.seq), e.recorded, e.finished, e.outcome, e.aborted_reason});
  std::cout << "run " << a.endings << ": " << rows.size() << " ending(s), in the order recorded\n";
  print_table(std::cout, t);
}

// Whether `db` is known to be the database the run in `dir` records into: the --db its run.json
// keeps. Without one the run took $RIG_HISTORY, the rig config, a hardware file's [history] url or
// the default, whichever applied where it ran, which run.json does not say (a review: a --record
// under another RIG_HISTORY finished the ending, and the station's database never got the row).
// `why_not`: what to say when it is not known to be.
bool the_runs_own_database(const std::string& dir, const std::string& db, std::string& why_not) {
  try {
    std::ifstream run_json(std::filesystem::path(dir) / "run.json");
    const nlohmann::json inv = parse_json_unique_keys(run_json);
    // --db as given, or (a run without it) the database as it resolved at the run's start
    std::string run_db = inv.value("db", std::string());
    const bool given = !run_db.empty();
    if (!given) run_db = inv.value("history_db", std::string());
    if (run_db.empty()) why_not = "its run.json does not say which database its run records into";
    else if (!history::same_database(db, run_db))
      why_not = "this is not the database its run records into (" + std::string(given ? "--db " : "") + run_db +
                (given ? ")" : ", as it resolved when the run started)");
    return why_not.empty();
  } catch (const std::exception&) {
    why_not = "its run.json cannot be read";
    return false;
  }
}

// A run whose ending stopped before its history row (.ending-pending, written by rig run): this
// record is that step when it goes into the run's own database. The list goes when it was the only
// step left and the rest of the ending is in place (junit.xml not staged, report.html there); else
// it stays for the run's resume, which finishes what is left (a review: --record left the list,
// and the resume's dry run said the ending was unfinished; a code review: a --record into another
// database removed it, and the station's never got the row).
void finish_ending_list(const std::string& dir, const std::string& db) {
  namespace fs = std::filesystem;
  const fs::path list = fs::path(dir) / kEndingPending;
  std::error_code ec;
  const std::optional<std::vector<std::string>> steps = pending_steps(dir);
  if (!steps) return;
  // `junit` is done once junit.xml.tmp is gone (checked below): a stop after its rename, before the
  // list was rewritten.
  std::vector<std::string> left = *steps;
  left.erase(std::remove(left.begin(), left.end(), std::string(kStepJunit)), left.end());
  const bool only_history = left == std::vector<std::string>{kStepHistory};
  std::string why_not;
  const bool own = the_runs_own_database(dir, db, why_not);
  if (only_history && own && !fs::exists(fs::path(dir) / "junit.xml.tmp", ec) &&
      fs::is_regular_file(fs::path(dir) / "report.html", ec) && fs::remove(list, ec))
    return;
  // The resume named only where it takes the ending up (a_resume_finishes; a code review: this
  // advised a resume that was refused, as `rig verify` did).
  if (a_resume_finishes(dir, *steps))
    std::cerr << "rig history: note: " << dir << "'s ending is not finished yet (" << kEndingPending
              << (own ? "" : "; " + why_not) << "): rig run --resume " << shell_word(dir)
              << " finishes it in the run's own database\n";
  else
    std::cerr << "rig history: note: " << dir << "'s ending is not finished (" << kEndingPending << ": "
              << fmt::format("{}", fmt::join(*steps, ", ")) << "), and " << kNothingFinishesIt << "\n";
}

// A sealed folder goes into the history only as the station sealed it (a review: a sealed FAIL
// whose passport was edited to PASS was recorded as PASS, `rig verify` alone saying otherwise).
// `rig verify`'s whole check, with the station's key; a sealed folder without one is refused.
// An unsealed folder is recorded as it lies (docs/seal.md: no seal, nothing vouched for), but
// not with a key: a station that seals every run and gives its key has asked for a sealed
// folder, and one whose seal was deleted was recorded PASS as it lay (a line integrator's
// review), as a resume with a key already refuses it.
void check_seal_before_recording(const HistoryArgs& a) {
  // seal.prev.json alone (a seal.json renamed away) is a sealed folder too (a re-test).
  const std::optional<std::string> seal_there = seal_in(a.record);
  const std::optional<seal::Key> key = station_key(a.seal_key, a.seal_key_given);
  if (!seal_there) {
    if (key)
      throw NotTheDatabase(a.record + " is not sealed (no seal.json): the station's key (--seal-key or RIG_SEAL_KEY) "
                           "cannot vouch for a folder it never sealed; nothing recorded (record it without the key, "
                           "RIG_SEAL_KEY unset, to take it as it lies)");
    return;
  }
  if (!key)
    throw NotTheDatabase(a.record + " is sealed (" + *seal_there + "): --record checks it with the station's key first "
                                    "(--seal-key FILE or RIG_SEAL_KEY); nothing recorded");
  const seal::Check c = check_run_folder_seal(a.record, *key);
  // A final seal the disk refused: an ending not finished, not a folder changed (a review).
  if (final_seal_owed(a.record, c, *key)) {
    const std::vector<std::string> steps = pending_steps(a.record).value_or(std::vector<std::string>{});
    throw NotTheDatabase(fmt::format("{}: its final seal was not written ({} lists: {}); nothing recorded ({})",
                                     a.record, kEndingPending, fmt::join(steps, ", "),
                                     a_resume_finishes(a.record, steps)
                                         ? "rig run --resume " + shell_word(a.record) + seal_key_words(a.seal_key) +
                                               " seals it"
                                         : std::string(kNothingFinishesIt)));
  }
  // With the key, where the line alone would be refused without it.
  if (!c.ok)
    throw NotTheDatabase(fmt::format("{} is not as the station sealed it ({}); nothing recorded (rig verify {}{} says "
                                     "more)",
                                     a.record, fmt::join(c.problems, "; "), shell_word(a.record),
                                     seal_key_words(a.seal_key)));
}

// The captures the passport names that are not in the folder, said once ("" when all are there):
// the record keeps what the passport names, so a folder whose captures were deleted is recorded
// with them listed (a review: the listing said "captures 10" of a folder holding none).
std::string captures_not_there(const std::string& dir, const nlohmann::json& passport) {
  if (!passport.contains("captures") || !passport["captures"].is_array()) return {};
  std::size_t named = 0;
  std::vector<std::string> gone;
  for (const nlohmann::json& c : passport["captures"]) {
    if (!c.is_string()) continue;
    ++named;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(std::filesystem::path(dir) / c.get<std::string>(), ec))
      gone.push_back(c.get<std::string>());
  }
  if (gone.empty()) return {};
  return fmt::format("{} of the {} captures the passport names {} not in {} ({}{}): recorded as the passport names "
                     "them; the run's raw records are incomplete",
                     gone.size(), named, gone.size() == 1 ? "is" : "are", dir, shown_ascii(gone.front()),
                     gone.size() > 1 ? ", ..." : "");
}

void record(const HistoryArgs& a) {
  // Not while a run or resume holds the folder: its passport may be about to change. The folder's
  // mistake, never the database's (it read "RIG_HISTORY: --record ...", a code review).
  // (A path that is no folder is named by the passport's reader, which says what it is.)
  std::optional<FolderLock> lock;
  nlohmann::json p;
  try {
    if (path_kind(a.record, "--record") == PathKind::directory) lock.emplace(a.record, "--record " + a.record);
    check_seal_before_recording(a);
    p = report::read_passport(a.record);  // the checks `rig report` makes: an edited passport is not history
    // Nor one whose limits were loosened with its verdict (each value then agrees with its own
    // limits): the passport is held to its folder's profile.toml and junit.xml, as a resume holds
    // an unsealed one (a technician's review: a FAIL edited to PASS was recorded PASS).
    if (const std::string why = passport_unlike_its_folder(a.record, p); !why.empty())
      throw ConfigError(a.record + "/passport.json: " + why +
                        ": the passport was changed after its run wrote it; nothing recorded");
  } catch (const ConfigError& e) {
    throw NotTheDatabase(e.what());
  }
  history::refuse_a_new_database_without_its_folder(a.db);  // as `rig run`
  const history::Recorded rec = history::record_run(a.db, p, a.record);
  for (const std::string& note : history::record_notes(rec, p)) std::cerr << "rig history: note: " << note << "\n";
  if (const std::string gone = captures_not_there(a.record, p); !gone.empty()) std::cerr << "rig history: note: " << gone << "\n";
  std::cout << "recorded run " << rec.id << " (" << p.value("serial", "") << ", " << p.value("outcome", "") << ") in "
            << a.db << "\n";
  finish_ending_list(a.record, a.db);
}

int run_history(const HistoryArgs& a, bool named) {
  if (!a.record.empty()) {
    record(a);
    return kExitPass;
  }
  if (a.endings > 0) {
    endings(a);
    return kExitPass;
  }
  // Reading never creates a database. A database that --db, $RIG_HISTORY or the rig config
  // names and is not there is a mistake (exit 2, from the reader: a typo there looked like an
  // empty history, a review); the built-in default merely does not exist until the first run records.
  if (const auto path = history::sqlite_path(a.db); !named && path && path_kind(*path, "history database") == PathKind::missing) {
    std::cout << "no runs recorded yet (" << a.db << " does not exist)\n";
    return kExitPass;
  }
  history::Filter f{a.no_serial ? std::optional<std::string>("") : opt(a.serial), opt(a.since), opt(a.until),
                    opt(a.outcome), opt(a.profile), a.limit};
  if (a.value.empty()) list(a, f);
  else trend(a, f);
  return kExitPass;
}

}  // namespace

void add_history(CLI::App& app, int& rc) {
  auto* sub = app.add_subcommand("history", "List recorded runs or trend a measurement (results database)");
  auto a = std::make_shared<HistoryArgs>();
  sub->add_option("--db", a->db, "Database URL: sqlite:PATH, PATH or postgresql://... (default: $RIG_HISTORY, "
                                  "[history] url in the rig config, $XDG_DATA_HOME/rig/history.sqlite, "
                                  "else ~/.local/share/rig/history.sqlite)");
  std::vector<CLI::Option*> query;
  query.push_back(sub->add_option("--serial", a->serial, "Only this DUT serial number"));
  query.push_back(sub->add_flag("--no-serial", a->no_serial,
                                "Only runs without a serial (stopped before the DUT said who it is)")
                      ->excludes(query.back()));
  query.push_back(sub->add_option("--since", a->since, "Only runs started at or after this ISO 8601 date/time (UTC if no zone)"));
  query.push_back(sub->add_option("--until", a->until, "Only runs started before this ISO 8601 date/time"));
  query.push_back(sub->add_option("--outcome", a->outcome, "Only runs whose latest ending has this outcome")
                      ->transform(CLI::IsMember({"PASS", "FAIL", "ABORTED", "ERROR"}, CLI::ignore_case)));
  query.push_back(sub->add_option("--profile", a->profile, "Only runs of this profile"));
  query.push_back(
      sub->add_option("--value", a->value, "Trend this passport measurement (e.g. in_run_b_allan) instead of listing runs"));
  // 0 would mean "no limit" to the query: a user who types --limit 0 asked for none, so N >= 1.
  query.push_back(sub->add_option("--limit", a->limit, "Only the newest N runs (N >= 1)")
                      ->check(whole_in("a number of runs", 1, std::numeric_limits<int>::max()).description("N >= 1")));
  query.push_back(sub->add_flag("--csv", a->csv, "Comma-separated output (RFC 4180) with every digit"));
  CLI::Option* rec =
      sub->add_option("--record", a->record, "Record the run folder DIR (its passport.json) into the database, then exit");
  CLI::Option* key = sub->add_option("--seal-key", a->seal_key,
                                     "With --record: the station's key, to check a sealed folder before recording it")
                         ->envname("RIG_SEAL_KEY");
  // A query option beside --record was ignored: `--record DIR --serial OTHER` recorded the folder
  // whatever its serial, exit 0 (a review). Refused as a usage error instead.
  for (CLI::Option* q : query) rec->excludes(q);
  CLI::Option* ends =
      sub->add_option("--endings", a->endings, "List every ending recorded for run ID (resumes, a folder put back)")
          ->check(whole_in("a run id", 1, std::numeric_limits<long long>::max()).description("ID"));
  ends->excludes(rec);
  for (CLI::Option* q : query)
    if (q->get_name() != "--csv") ends->excludes(q);
  sub->callback([&rc, a, key] {
    a->seal_key_given = key->count() > 0;
    // The options' own mistakes before any database is named: the query's check of a date read
    // as the database's ("RIG_HISTORY: --since '2026-13-01' ...", a review).
    try {
      for (const auto& [opt_name, text] : {std::pair<const char*, const std::string&>{"--since", a->since}, {"--until", a->until}})
        if (!text.empty()) history::iso8601_bound(text, opt_name);
    } catch (const ConfigError& e) {
      throw NotTheDatabase(e.what());
    }
    const bool db_given = !a->db.empty();  // (an empty --db is refused as such by main.cpp)
    HistorySource source{a->db};
    if (!db_given) source = default_history();
    a->db = source.url;
    try {
      rc = run_history(*a, db_given || a->db != history::builtin_db_url());
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
