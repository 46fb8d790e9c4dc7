// The results database: every run recorded with its passport values, outcome, profile,
// plant, software version, times, run folder and capture paths. SQLite by default (one
// file), PostgreSQL for a line of rigs reporting to one server. Schema and migrations:
// docs/history.md.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace rig::history {

// $RIG_HISTORY if set; else `[history] url` of the rig config ($RIG_CONFIG, or
// ~/.config/rig/rig.toml if present; a relative path is taken from the config's folder);
// else sqlite:$XDG_DATA_HOME/rig/history.sqlite (or ~/.local/share/rig/history.sqlite).
std::string default_db_url();
// The database used when nothing names one: sqlite:$XDG_DATA_HOME/rig/history.sqlite (or
// ~/.local/share/..., or the working folder without a HOME).
std::string builtin_db_url();
// A new SQLite database goes into a folder that is there, but for the built-in default, whose
// folders are made with it: a typo in --db, $RIG_HISTORY or [history] url made its folders and a
// database the station's history never reads (a technician's review; as root, at /). ConfigError
// for `url` naming a file that is not there in a folder that is not there either; `rig run` and
// `rig history --record` ask before they write.
void refuse_a_new_database_without_its_folder(const std::string& url);

// $RIG_HISTORY when set; nullopt when unset; set but empty is a ConfigError saying so (not read
// as unset, as an empty RIG_SEAL_KEY is refused).
std::optional<std::string> history_from_environment();

// The rig config default_db_url reads: $RIG_CONFIG if set (ConfigError if it is not there), else
// ~/.config/rig/rig.toml if it exists, else none. A path that cannot be reached (a $HOME the user
// may not enter) is a ConfigError naming it, not "no config": the runs would be recorded into
// another database than the station's.
std::optional<std::string> rig_config_path();

// What recording a run did.
struct Recorded {
  long long id = 0;  // the run's id in the database
  int endings = 0;   // endings kept for the run, this one included
  // Set when the run was recorded before with a verdict (PASS or FAIL) and this ending's outcome
  // is another one (a folder put back to an earlier state and resumed): the listing now shows
  // this ending; the earlier one is kept among the run's endings.
  std::optional<std::string> replaced_verdict;
  std::string replaced_finished;
  // Runs recorded from another folder with the same serial and start time: a copy of the run's
  // folder recorded too (their id and folder), which the listing and statistics count twice.
  std::vector<std::pair<long long, std::string>> elsewhere;
};

// Records one run (also aborted ones). `db_url`: "sqlite:PATH", a plain path, or
// "postgresql://..." / "postgres://...". Recording the same run (same run folder and
// start time) again replaces its row in `runs` (the same id) and adds the ending to the run's
// endings, unless it is the last ending recorded again (same outcome, finish time and reason).
// Throws rig::ConfigError for a bad URL or an unreachable/unwritable database and
// for a passport without the fields the schema needs.
Recorded record_run(const std::string& db_url, const nlohmann::json& passport, const std::string& run_dir);

// "run N was recorded as FAIL (finished T); this ending (ABORTED) is now its listed outcome ..."
std::string replaced_verdict_note(const Recorded& rec, const std::string& outcome);
// What recording `passport` has to say (the replaced verdict, each copy recorded elsewhere), one
// line each: `rig run` and `rig history --record` say the same.
std::vector<std::string> record_notes(const Recorded& rec, const nlohmann::json& passport);

// One ending of a run, in the order recorded (seq from 0).
struct EndingRow {
  long long seq = 0;
  std::string outcome, finished, recorded, aborted_reason;
};
// The endings of run `run_id` (empty: no such run).
std::vector<EndingRow> endings_of(const std::string& db_url, long long run_id);

// Query filters shared by the listing and the trend.
struct Filter {
  std::optional<std::string> serial;  // exact serial number
  std::optional<std::string> since;   // ISO date or date-time (UTC), inclusive
  std::optional<std::string> until;   // ISO date or date-time (UTC), exclusive
  std::optional<std::string> outcome; // PASS, FAIL, ABORTED, ERROR
  std::optional<std::string> profile;
  int limit = 0;                      // 0 = no limit (newest first when limited)
};

struct RunRow {
  long long id = 0;
  std::string serial, profile, plant, software, station, started, finished, outcome, run_dir, aborted_reason;
  std::vector<std::string> captures;
  std::vector<std::string> earlier;  // the outcomes of the run's earlier endings, oldest first
};

struct ValueRow {
  long long run_id = 0;
  std::string serial, started, outcome, profile;  // run's
  std::optional<double> value, lo, hi, limit_min, limit_max;
  std::string unit, value_outcome, reason;
};

// The reading functions below open the database read-only and never create one: a
// missing SQLite file is a rig::ConfigError naming it.
// Runs matching `f`, oldest first.
std::vector<RunRow> list_runs(const std::string& db_url, const Filter& f);
// One measurement across the runs matching `f`, oldest first (the trend).
std::vector<ValueRow> trend(const std::string& db_url, const std::string& value_name, const Filter& f);
// Names of all measurements recorded (for `rig history --value` help and errors).
std::vector<std::string> value_names(const std::string& db_url);

// The schema version this build writes and migrates to.
int current_schema_version();
// Opens (creating and migrating if needed) and returns the schema version found before
// migrating (0 = new database).
int migrate(const std::string& db_url);

}  // namespace rig::history
