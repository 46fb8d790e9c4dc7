#include "rig/report/history.hpp"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>

#include "rig/core/path_kind.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/report/db.hpp"
#include "rig/report/db_url.hpp"
#include "rig/report/timefmt.hpp"

namespace rig::history {

namespace fs = std::filesystem;
using nlohmann::json;

// ------------------------------------------------------------------ schema and migrations
// Each migration takes the schema from version N-1 to N inside one transaction. Never edit
// a released step: add a new one (docs/history.md lists them). `{id}` is the dialect's
// auto-increment key; everything else is SQL both SQLite and PostgreSQL accept.
namespace {

struct Migration {
  int version;
  std::vector<std::string> ddl;
  std::function<void(Db&)> data;  // optional data step after the DDL
};

// v2 data step: capture paths and the abort reason were only inside the stored passport.
void backfill_v2(Db& db) {
  for (const Row& r : db.query("SELECT id, passport FROM runs")) {
    const int64_t id = as_int(r[0]).value_or(0);
    const json p = json::parse(as_text(r[1]), nullptr, false);
    if (!p.is_object()) continue;
    if (p.contains("captures") && p["captures"].is_array()) {
      int64_t seq = 0;
      for (const json& c : p["captures"])
        if (c.is_string()) db.exec("INSERT INTO run_captures (run_id, seq, path) VALUES (?, ?, ?)", {id, seq++, c.get<std::string>()});
    }
    if (p.contains("aborted_reason") && p["aborted_reason"].is_string())
      db.exec("UPDATE runs SET aborted_reason = ? WHERE id = ?", {p["aborted_reason"].get<std::string>(), id});
  }
}

const std::vector<Migration>& migrations() {
  static const std::vector<Migration> m = {
      {1,
       {"CREATE TABLE runs (id {id}, serial TEXT NOT NULL, profile TEXT, plant TEXT, software TEXT, "
        "started TEXT, finished TEXT, outcome TEXT NOT NULL, run_dir TEXT NOT NULL, passport TEXT NOT NULL)",
        "CREATE UNIQUE INDEX runs_dir_started ON runs (run_dir, started)",
        "CREATE INDEX runs_serial_started ON runs (serial, started)",
        "CREATE TABLE run_values (run_id BIGINT NOT NULL REFERENCES runs (id) ON DELETE CASCADE, "
        "name TEXT NOT NULL, value DOUBLE PRECISION, unit TEXT, lo DOUBLE PRECISION, hi DOUBLE PRECISION, "
        "limit_min DOUBLE PRECISION, limit_max DOUBLE PRECISION, outcome TEXT, reason TEXT, "
        "PRIMARY KEY (run_id, name))"},
       nullptr},
      {2,
       {"ALTER TABLE runs ADD COLUMN station TEXT", "ALTER TABLE runs ADD COLUMN aborted_reason TEXT",
        "ALTER TABLE runs ADD COLUMN recorded TEXT",
        "CREATE TABLE run_captures (run_id BIGINT NOT NULL REFERENCES runs (id) ON DELETE CASCADE, "
        "seq INTEGER NOT NULL, path TEXT NOT NULL, PRIMARY KEY (run_id, seq))",
        "CREATE INDEX run_values_name ON run_values (name)"},
       backfill_v2},
      // v3: every ending of a run kept (a resume replaced the run's row, so a FAIL recorded
      // before a folder was put back to an earlier state and resumed was gone, a review); the
      // row in `runs` is the latest ending, run_endings each one in the order recorded.
      {3,
       {"CREATE TABLE run_endings (run_id BIGINT NOT NULL REFERENCES runs (id) ON DELETE CASCADE, "
        "seq INTEGER NOT NULL, outcome TEXT NOT NULL, finished TEXT, recorded TEXT, aborted_reason TEXT, "
        "passport TEXT NOT NULL, PRIMARY KEY (run_id, seq))",
        "INSERT INTO run_endings (run_id, seq, outcome, finished, recorded, aborted_reason, passport) "
        "SELECT id, 0, outcome, finished, recorded, aborted_reason, passport FROM runs"},
       nullptr},
      // v4: a run is its folder, start time, DUT and station: two stations sharing a database,
      // each writing a folder of the same path in the same second, or a line that moves a folder
      // away and starts the next DUT in it within the second, had their runs merged into one row,
      // the first DUT's record gone (a review).
      {4, {"DROP INDEX runs_dir_started", "CREATE UNIQUE INDEX runs_identity ON runs (run_dir, started, serial, station)"},
       nullptr},
  };
  return m;
}

std::string expand(const Db& db, std::string sql) {
  for (std::size_t p; (p = sql.find("{id}")) != std::string::npos;) sql.replace(p, 4, db.dialect_type("id"));
  return sql;
}

int schema_version(Db& db) {
  if (!db.has_table("schema_version")) return 0;
  const auto rows = db.query("SELECT MAX(version) FROM schema_version");
  return rows.empty() ? 0 : static_cast<int>(as_int(rows[0][0]).value_or(0));
}

// Brings the database to the current version; returns the version found.
int migrate_db(Db& db) {
  const int target = current_schema_version();
  int found = schema_version(db);
  if (found == target) return found;  // the common case: no lock taken
  Transaction tx(db);
  db.exec("CREATE TABLE IF NOT EXISTS schema_version (version INTEGER NOT NULL PRIMARY KEY, applied TEXT NOT NULL)");
  found = schema_version(db);  // re-read under the lock: another rig may have migrated
  if (found > target)
    throw ConfigError(db.where() + ": history schema version " + std::to_string(found) +
                      " is newer than this rig understands (" + std::to_string(target) + "); upgrade rig");
  for (const Migration& m : migrations()) {
    if (m.version <= found) continue;
    for (const std::string& s : m.ddl) db.exec(expand(db, s));
    if (m.data) m.data(db);
    db.exec("INSERT INTO schema_version (version, applied) VALUES (?, ?)", {int64_t{m.version}, utc_now_iso8601()});
  }
  tx.commit();
  return found;
}

std::unique_ptr<Db> open_migrated(const std::string& url) {
  auto db = open_db(url);
  migrate_db(*db);
  return db;
}

// Reading commands never create a database: the SQLite file must exist and is opened
// read-only. Only a database of an older schema is reopened for writing, to migrate it.
std::unique_ptr<Db> open_for_reading(const std::string& url) {
  auto db = open_db(url, Access::ReadOnly);
  const int found = schema_version(*db);
  if (found == current_schema_version()) return db;
  if (found == 0) throw ConfigError(db->where() + ": not a rig history database (no schema_version table)");
  db.reset();
  return open_migrated(url);  // older: migrated; newer: refused with the version found
}

// ------------------------------------------------------------------ passport -> rows
Value opt_number(const json& j, const char* key) {
  if (!j.is_object() || !j.contains(key) || !j[key].is_number()) return std::monostate{};
  return j[key].get<double>();
}
Value opt_text(const json& j, const char* key) {
  if (!j.is_object() || !j.contains(key) || j[key].is_null()) return std::monostate{};
  return j[key].is_string() ? j[key].get<std::string>() : j[key].dump();
}
Value opt_time(const json& j, const char* key) {
  Value v = opt_text(j, key);
  if (const auto* s = std::get_if<std::string>(&v))
    if (auto n = normalize_iso8601(*s)) return *n;
  return v;
}

std::string station_name(const json& passport) {
  if (passport.contains("station") && passport["station"].is_string()) return passport["station"].get<std::string>();
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0) return "";
  return host;
}

std::string where_clause(const Filter& f, std::vector<Value>& params) {
  std::string w = " WHERE 1 = 1";
  auto add = [&](const std::optional<std::string>& v, const char* sql) {
    if (!v) return;
    w += sql;
    params.emplace_back(*v);
  };
  auto time_bound = [](const std::optional<std::string>& t, const char* what) -> std::optional<std::string> {
    if (!t) return std::nullopt;
    return iso8601_bound(*t, what);
  };
  add(f.serial, " AND r.serial = ?");
  add(time_bound(f.since, "--since"), " AND r.started >= ?");
  add(time_bound(f.until, "--until"), " AND r.started < ?");
  add(f.outcome, " AND r.outcome = ?");
  add(f.profile, " AND r.profile = ?");
  return w;
}

// Oldest first; with a limit, the newest `limit` rows (still oldest first).
std::string ordered(const std::string& select, const Filter& f, std::vector<Value>& params) {
  if (f.limit <= 0) return select + " ORDER BY r.started, r.id";
  params.emplace_back(int64_t{f.limit});
  return "SELECT * FROM (" + select + " ORDER BY r.started DESC, r.id DESC LIMIT ?) AS newest ORDER BY newest.started, newest.id";
}

// The runs a listing shows, for its child tables (captures, endings): `where_clause`, and with a
// limit only the newest `limit` runs' rows (their queries read every run's, filtered after, a
// code review). The inner query's alias shadows the outer one's.
std::string listed(const Filter& f, std::vector<Value>& params) {
  std::string w = where_clause(f, params);
  if (f.limit <= 0) return w;
  const std::string inner = where_clause(f, params);
  params.emplace_back(int64_t{f.limit});
  return w + " AND r.id IN (SELECT newest.id FROM (SELECT r.id FROM runs r" + inner +
         " ORDER BY r.started DESC, r.id DESC LIMIT ?) AS newest)";
}

std::optional<double> num(const Value& v) { return as_double(v); }

// The run folder as the database keys it: absolute, its links resolved, so that "r1", "./r1/" and
// a link to it are one run.
std::string run_dir_key(const std::string& run_dir) {
  std::error_code ec;
  const fs::path dir = fs::weakly_canonical(fs::absolute(run_dir), ec);
  return (ec ? fs::absolute(run_dir) : dir).string();
}

}  // namespace

int current_schema_version() { return migrations().back().version; }

int migrate(const std::string& db_url) {
  auto db = open_db(db_url);
  return migrate_db(*db);
}

Recorded record_run(const std::string& db_url, const json& passport, const std::string& run_dir) {
  if (!passport.is_object()) throw ConfigError("history: the passport is not a JSON object");
  for (const char* key : {"serial", "outcome"})
    if (!passport.contains(key) || !passport[key].is_string())
      throw ConfigError(std::string("history: the passport has no '") + key + "' string");
  const std::string dir = run_dir_key(run_dir);

  auto db = open_migrated(db_url);
  Transaction tx(*db);
  const Value started = opt_time(passport, "started"), finished = opt_time(passport, "finished");
  const Value reason = opt_text(passport, "aborted_reason");
  const std::string outcome = passport["outcome"].get<std::string>(), now = utc_now_iso8601(), text = passport.dump();
  const Value software = passport.contains("software") && passport["software"].is_string()
                             ? Value(passport["software"].get<std::string>())
                             : Value(std::string("rig ") + RIG_VERSION);
  std::vector<Value> row = {passport["serial"].get<std::string>(), opt_text(passport, "profile"),
                            opt_text(passport, "plant"), software, started, finished,
                            outcome, dir, text, station_name(passport), reason, now};
  // A run recorded again (a resume, `--record` after a database outage) keeps its id, so that a
  // reference to it (a quality record, a ticket) stays valid; it used to get a new one each time.
  // A run is its folder, start time, DUT and station (v4); a row from before v2 has no station,
  // and one recorded before the DUT gave its serial (a run stopped in bring-up, then resumed) has
  // none either: the same run (a re-test: it became a second row).
  const auto was = db->query("SELECT id FROM runs WHERE run_dir = ? AND started IS NOT DISTINCT FROM ? AND "
                             "(serial = ? OR serial = '') AND (station IS NOT DISTINCT FROM ? OR station IS NULL) "
                             "ORDER BY id",
                             {dir, started, passport["serial"].get<std::string>(), station_name(passport)});
  Recorded rec;
  if (was.empty()) {
    rec.id = as_int(db->query("INSERT INTO runs (serial, profile, plant, software, started, finished, outcome, run_dir, "
                              "passport, station, aborted_reason, recorded) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) "
                              "RETURNING id",
                              row)
                        .at(0)
                        .at(0))
                 .value_or(0);
  } else {
    rec.id = as_int(was[0][0]).value_or(0);
    // Rows of the same run beyond the first (runs without a start time: the unique index lets
    // NULLs repeat) are folded into it, their endings kept after its own (a code review: the
    // delete's cascade took them).
    for (std::size_t i = 1; i < was.size(); ++i) {
      const int64_t next =
          as_int(db->query("SELECT COALESCE(MAX(seq), -1) + 1 FROM run_endings WHERE run_id = ?", {rec.id}).at(0).at(0))
              .value_or(0);
      db->exec("UPDATE run_endings SET run_id = ?, seq = seq + ? WHERE run_id = ?", {rec.id, next, was[i][0]});
      db->exec("DELETE FROM runs WHERE id = ?", {was[i][0]});
    }
    db->exec("DELETE FROM run_values WHERE run_id = ?", {rec.id});
    db->exec("DELETE FROM run_captures WHERE run_id = ?", {rec.id});
    // GCC 12 at -O3 calls the strings of the variants this push_back moves "maybe uninitialized"
    // (a false positive that comes and goes with the function's inlining; the values are all set).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
    row.push_back(rec.id);
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
    db->exec("UPDATE runs SET serial = ?, profile = ?, plant = ?, software = ?, started = ?, finished = ?, outcome = ?, "
             "run_dir = ?, passport = ?, station = ?, aborted_reason = ?, recorded = ? WHERE id = ?",
             row);
  }
  // The ending, unless it is the last one recorded again (an ending finished by its resume, a
  // second --record): the same passport (two endings within one second had the same outcome and
  // finish time, a review).
  const auto last = db->query("SELECT seq, passport FROM run_endings WHERE run_id = ? ORDER BY seq DESC LIMIT 1",
                              {rec.id});
  const bool again = !last.empty() && as_text(last[0][1]) == text;
  if (!again) {
    // A verdict recorded before that this new ending does not repeat (a folder put back and
    // resumed), said even with other endings between them (FAIL, ABORTED, then PASS: a review).
    const auto verdict = db->query("SELECT outcome, finished FROM run_endings WHERE run_id = ? AND outcome IN ('PASS', "
                                   "'FAIL') ORDER BY seq DESC LIMIT 1",
                                   {rec.id});
    if (!verdict.empty() && as_text(verdict[0][0]) != outcome) {
      rec.replaced_verdict = as_text(verdict[0][0]);
      rec.replaced_finished = as_text(verdict[0][1]);
    }
    db->exec("INSERT INTO run_endings (run_id, seq, outcome, finished, recorded, aborted_reason, passport) "
             "VALUES (?, ?, ?, ?, ?, ?, ?)",
             {rec.id, last.empty() ? int64_t{0} : as_int(last[0][0]).value_or(0) + 1, outcome, finished, now, reason, text});
  }
  // The same run recorded from another folder (a copy), read in this transaction: it was a second
  // opening of the database by each caller.
  for (const Row& r : db->query("SELECT id, run_dir FROM runs WHERE serial = ? AND started IS NOT DISTINCT FROM ? AND "
                                "run_dir <> ? ORDER BY id",
                                {passport["serial"].get<std::string>(), started, dir}))
    rec.elsewhere.emplace_back(as_int(r[0]).value_or(0), as_text(r[1]));
  rec.endings = static_cast<int>(
      as_int(db->query("SELECT COUNT(*) FROM run_endings WHERE run_id = ?", {rec.id}).at(0).at(0)).value_or(0));

  if (passport.contains("values") && passport["values"].is_object()) {
    for (const auto& [name, v] : passport["values"].items()) {
      Value lmin, lmax;
      if (v.is_object() && v.contains("limits") && v["limits"].is_array() && v["limits"].size() == 2) {
        if (v["limits"][0].is_number()) lmin = v["limits"][0].get<double>();
        if (v["limits"][1].is_number()) lmax = v["limits"][1].get<double>();
      }
      db->exec(
          "INSERT INTO run_values (run_id, name, value, unit, lo, hi, limit_min, limit_max, outcome, reason) "
          "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
          {rec.id, name, opt_number(v, "value"), opt_text(v, "unit"), opt_number(v, "lo"), opt_number(v, "hi"), lmin, lmax,
           opt_text(v, "outcome"), opt_text(v, "reason")});
    }
  }
  if (passport.contains("captures") && passport["captures"].is_array()) {
    int64_t seq = 0;
    for (const json& c : passport["captures"])
      if (c.is_string()) db->exec("INSERT INTO run_captures (run_id, seq, path) VALUES (?, ?, ?)", {rec.id, seq++, c.get<std::string>()});
  }
  tx.commit();
  return rec;
}

std::vector<std::string> record_notes(const Recorded& rec, const json& passport) {
  std::vector<std::string> out;
  if (rec.replaced_verdict) out.push_back(replaced_verdict_note(rec, passport.value("outcome", "")));
  for (const auto& [other, dir] : rec.elsewhere)
    out.push_back("the same run (serial " + passport.value("serial", std::string()) + ", started " +
                  passport.value("started", std::string()) + ") is also recorded from " + dir + " (run " +
                  std::to_string(other) + "): a copy of its folder, or another run of this DUT started in the same second "
                  "(two stations, the emulated plant's one serial)? The listing and the statistics count it twice");
  return out;
}

std::vector<RunRow> list_runs(const std::string& db_url, const Filter& f) {
  auto db = open_for_reading(db_url);
  std::vector<Value> params;
  const std::string w = where_clause(f, params);
  const std::string select =
      "SELECT r.id, r.serial, r.profile, r.plant, r.software, r.station, r.started, r.finished, r.outcome, r.run_dir, "
      "r.aborted_reason FROM runs r" + w;
  std::vector<RunRow> out;
  std::map<int64_t, std::size_t> index;
  for (const Row& r : db->query(ordered(select, f, params), params)) {
    RunRow x;
    x.id = as_int(r[0]).value_or(0);
    x.serial = as_text(r[1]);
    x.profile = as_text(r[2]);
    x.plant = as_text(r[3]);
    x.software = as_text(r[4]);
    x.station = as_text(r[5]);
    x.started = as_text(r[6]);
    x.finished = as_text(r[7]);
    x.outcome = as_text(r[8]);
    x.run_dir = as_text(r[9]);
    x.aborted_reason = as_text(r[10]);
    index[x.id] = out.size();
    out.push_back(std::move(x));
  }
  std::vector<Value> cparams;
  const std::string cw = listed(f, cparams);
  for (const Row& r : db->query("SELECT c.run_id, c.path FROM run_captures c JOIN runs r ON r.id = c.run_id" + cw +
                                    " ORDER BY c.run_id, c.seq",
                                cparams)) {
    auto it = index.find(as_int(r[0]).value_or(-1));
    if (it != index.end()) out[it->second].captures.push_back(as_text(r[1]));
  }
  std::vector<Value> eparams;
  const std::string ew = listed(f, eparams);
  for (const Row& r : db->query("SELECT e.run_id, e.outcome FROM run_endings e JOIN runs r ON r.id = e.run_id" + ew +
                                    " ORDER BY e.run_id, e.seq",
                                eparams)) {
    auto it = index.find(as_int(r[0]).value_or(-1));
    if (it != index.end()) out[it->second].earlier.push_back(as_text(r[1]));
  }
  for (RunRow& x : out)
    if (!x.earlier.empty()) x.earlier.pop_back();  // the last ending is the row itself
  return out;
}

std::string replaced_verdict_note(const Recorded& rec, const std::string& outcome) {
  return "run " + std::to_string(rec.id) + " was recorded as " + rec.replaced_verdict.value_or("") +
         (rec.replaced_finished.empty() ? std::string() : " (finished " + rec.replaced_finished + ")") +
         "; this ending (" + outcome + ") is now its listed outcome, and the earlier one is kept: rig history --endings " +
         std::to_string(rec.id);
}

std::vector<EndingRow> endings_of(const std::string& db_url, long long run_id) {
  auto db = open_for_reading(db_url);
  std::vector<EndingRow> out;
  for (const Row& r : db->query("SELECT seq, outcome, finished, recorded, aborted_reason FROM run_endings "
                                "WHERE run_id = ? ORDER BY seq",
                                {int64_t{run_id}}))
    out.push_back({as_int(r[0]).value_or(0), as_text(r[1]), as_text(r[2]), as_text(r[3]), as_text(r[4])});
  return out;
}

std::vector<ValueRow> trend(const std::string& db_url, const std::string& value_name, const Filter& f) {
  auto db = open_for_reading(db_url);
  std::vector<Value> params;
  const std::string w = where_clause(f, params) + " AND v.name = ?";
  params.emplace_back(value_name);
  const std::string select =
      "SELECT r.id, r.serial, r.outcome, v.value, v.lo, v.hi, r.started, v.limit_min, v.limit_max, v.unit, "
      "v.outcome, v.reason, r.profile FROM run_values v JOIN runs r ON r.id = v.run_id" + w;
  std::vector<ValueRow> out;
  for (const Row& r : db->query(ordered(select, f, params), params)) {
    ValueRow x;
    x.run_id = as_int(r[0]).value_or(0);
    x.serial = as_text(r[1]);
    x.outcome = as_text(r[2]);
    x.value = num(r[3]);
    x.lo = num(r[4]);
    x.hi = num(r[5]);
    x.started = as_text(r[6]);
    x.limit_min = num(r[7]);
    x.limit_max = num(r[8]);
    x.unit = as_text(r[9]);
    x.value_outcome = as_text(r[10]);
    x.reason = as_text(r[11]);
    x.profile = as_text(r[12]);
    out.push_back(std::move(x));
  }
  return out;
}

std::vector<std::string> value_names(const std::string& db_url) {
  auto db = open_for_reading(db_url);
  std::vector<std::string> out;
  for (const Row& r : db->query("SELECT DISTINCT name FROM run_values ORDER BY name")) out.push_back(as_text(r[0]));
  return out;
}

// ------------------------------------------------------------------ default location
std::optional<std::string> rig_config_path() {
  // Set but empty is not "unset" (a script's RIG_CONFIG=$UNSET_VAR read the home config without a
  // word; an empty RIG_SEAL_KEY was refused, a review): said, as every empty value is.
  if (const char* c = std::getenv("RIG_CONFIG"); c && !*c)
    throw ConfigError("RIG_CONFIG is set but empty: name the rig config file, or unset RIG_CONFIG");
  if (const char* c = std::getenv("RIG_CONFIG"); c && *c) {
    if (path_kind(c, "RIG_CONFIG names") == PathKind::missing)
      throw ConfigError("RIG_CONFIG names '" + std::string(c) + "', which does not exist");
    return std::string(c);
  }
  if (const char* home = std::getenv("HOME"); home && *home) {
    const std::string p = (fs::path(home) / ".config/rig/rig.toml").string();
    try {
      if (path_kind(p, "rig config") != PathKind::missing) return p;
    } catch (const ConfigError& e) {
      throw ConfigError(std::string(e.what()) + "; set RIG_CONFIG or RIG_HISTORY to name another, or HOME to yours");
    }
  }
  return std::nullopt;
}

std::optional<std::string> history_from_environment() {
  const char* e = std::getenv("RIG_HISTORY");
  if (!e) return std::nullopt;
  if (!*e)  // as RIG_CONFIG (rig_config_path)
    throw ConfigError("RIG_HISTORY is set but empty: name the history database (sqlite:FILE or postgresql://...), "
                      "or unset RIG_HISTORY");
  return std::string(e);
}

std::string default_db_url() {
  if (std::optional<std::string> e = history_from_environment()) return *e;
  fs::path config;
  if (const std::optional<std::string> c = rig_config_path()) config = *c;
  if (!config.empty()) {
    const toml::table t = cfg::parse_file(config.string());
    if (const toml::table* h = cfg::get_table(t, "history")) {
      cfg::check_keys(*h, {"url"}, "history");
      std::string url = cfg::get_string(*h, "url");
      if (url.empty()) throw ConfigError(cfg::where(*h->get("url")) + ": [history] url is empty");
      // A relative SQLite path is relative to the config file, not to the working folder.
      if (const std::string why = url_problem(url); !why.empty())  // at the config's line ("~/" with no $HOME too)
        throw ConfigError(cfg::where(*h->get("url")) + ": 'url' = '" + mask_password(url) + "': " + why);
      const std::optional<std::string> path = sqlite_path(url);  // nullopt: PostgreSQL
      if (path && fs::path(*path).is_relative()) return "sqlite:" + (config.parent_path() / *path).string();
      return path ? "sqlite:" + *path : url;
    }
  }
  return builtin_db_url();
}

void refuse_a_new_database_without_its_folder(const std::string& url) {
  const std::optional<SqliteFile> f = sqlite_file(url);
  if (f && !f->exists && !f->missing_folder.empty() && url != builtin_db_url())
    throw ConfigError("history database " + f->path + ": its folder " + f->missing_folder +
                      " does not exist (a typo?); the rig creates a new database only in a folder that is there: "
                      "create it first to start one there");
}

std::string builtin_db_url() {
  const char* home = std::getenv("HOME");
  fs::path data;
  if (const char* x = std::getenv("XDG_DATA_HOME"); x && *x) data = x;
  else if (home && *home) data = fs::path(home) / ".local/share";
  else data = fs::current_path();
  return "sqlite:" + (data / "rig" / "history.sqlite").string();
}

}  // namespace rig::history
