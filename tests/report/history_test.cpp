// The results database on SQLite: round trip, migration from an older schema, errors,
// the default location, concurrent writers and the `rig history` command's output.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <thread>

#include "app/commands.hpp"
#include "rig/report/db.hpp"
#include "rig/report/db_url.hpp"
#include "rig/report/history.hpp"
#include "rig/report/timefmt.hpp"
#include "tests/report/history_cases.hpp"

namespace {

using nlohmann::json;
using rig::test::TempDir;
namespace h = rig::history;
namespace fs = std::filesystem;

// Runs raw SQL on a SQLite file (to build old schemas and to inspect the result).
void raw_sql(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  char* err = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err);
  const std::string msg = err ? err : "";
  sqlite3_free(err);
  sqlite3_close(db);
  ASSERT_EQ(rc, SQLITE_OK) << msg;
}

std::string raw_scalar(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  sqlite3_open(path.c_str(), &db);
  sqlite3_stmt* st = nullptr;
  std::string out;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &st, nullptr) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW) {
    const auto* t = sqlite3_column_text(st, 0);
    out = t ? reinterpret_cast<const char*>(t) : "NULL";
  }
  sqlite3_finalize(st);
  sqlite3_close(db);
  return out;
}

TEST(HistorySqlite, RoundTripFiltersAndTrend) {
  TempDir d;
  rig::test::history_round_trip("sqlite:" + (d.path / "db" / "history.sqlite").string(), d.path.string());
  EXPECT_TRUE(std::filesystem::exists(d.path / "db" / "history.sqlite"));  // folder created
}

// Rows an older rig left for one run without a start time (NULL started repeats under the unique
// index; it added a row per record) are folded into the first when the run is recorded again,
// their endings kept after its own (a code review: the delete's cascade took them).
TEST(HistorySqlite, RowsOfOneRunWithoutAStartTimeAreFoldedWithTheirEndings) {
  TempDir d;
  const std::string path = (d.path / "h.sqlite").string(), dir = (d.path / "ns").string();
  json p = rig::test::fixture_passport("NS-1", "ABORTED", "2026-11-01T08:00:00Z");
  p.erase("started");
  ASSERT_EQ(h::record_run(path, p, dir).id, 1);
  json failed = p;
  failed["outcome"] = "FAIL";
  std::string pj = failed.dump();
  for (std::size_t i = 0; (i = pj.find('\'', i)) != std::string::npos; i += 2) pj.insert(i, "'");  // SQL quoting
  raw_sql(path, "INSERT INTO runs (id, serial, outcome, run_dir, passport) SELECT 2, serial, 'FAIL', run_dir, passport "
                "FROM runs WHERE id = 1; INSERT INTO run_endings (run_id, seq, outcome, passport) VALUES (2, 0, 'FAIL', '" +
                    pj + "');");
  const h::Recorded r = h::record_run(path, p, dir);
  EXPECT_EQ(r.id, 1);
  EXPECT_EQ(raw_scalar(path, "SELECT COUNT(*) FROM runs"), "1");
  const auto e = h::endings_of(path, 1);
  ASSERT_EQ(e.size(), 3u);  // its own, the folded row's, then this one (after a FAIL: another ending)
  EXPECT_EQ(e[0].outcome, "ABORTED");
  EXPECT_EQ(e[1].outcome, "FAIL");
  EXPECT_EQ(e[2].outcome, "ABORTED");
  EXPECT_EQ(r.endings, 3);
}

TEST(HistorySqlite, EveryEndingOfARunIsKept) {
  TempDir d;
  rig::test::history_keeps_every_ending("sqlite:" + (d.path / "h.sqlite").string(), d.path.string());
}

TEST(HistorySqlite, RunsOfOneFolderAndSecondOnTwoStationsOrDutsAreTwoRuns) {
  TempDir d;
  rig::test::history_tells_runs_of_one_folder_and_second_apart("sqlite:" + (d.path / "h.sqlite").string(),
                                                               d.path.string());
}

namespace {

// Seconds `record_run` of a fresh passport took to give up on `path` (another writer holds it).
double seconds_to_give_up(const std::string& path, const std::string& serial, const TempDir& d) {
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_THROW(h::record_run(path, rig::test::fixture_passport(serial), d.path.string()), std::exception);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// A history file with one run, and another connection holding it in an exclusive transaction.
sqlite3* recorded_and_held(const std::string& path, const TempDir& d) {
  h::record_run(path, rig::test::fixture_passport(), d.path.string());
  sqlite3* holder = nullptr;
  if (sqlite3_open(path.c_str(), &holder) != SQLITE_OK ||
      sqlite3_exec(holder, "BEGIN EXCLUSIVE", nullptr, nullptr, nullptr) != SQLITE_OK)
    ADD_FAILURE() << "could not hold " << path;
  return holder;
}

}  // namespace

// The wait for another writer's lock: 10 s by default, shorter once set (a stopped run's
// ending: a locked database held a SIGTERM'd run 10 s, a line integrator's review).
TEST(HistorySqlite, TheLockWaitIsWhatWasSet) {
  TempDir d;
  const std::string path = (d.path / "h.sqlite").string();
  sqlite3* holder = recorded_and_held(path, d);
  const auto attempt = [&] { return seconds_to_give_up(path, "LOCKED-1", d); };
  h::set_lock_wait_ms(300);
  const double short_wait = attempt();
  h::set_lock_wait_ms(1500);
  const double longer_wait = attempt();
  h::set_lock_wait_ms(10000);
  sqlite3_exec(holder, "ROLLBACK", nullptr, nullptr, nullptr);
  sqlite3_close(holder);
  try {  // the statement by its kind, the database's reason after it
    h::set_lock_wait_ms(100);
    sqlite3* again = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &again), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(again, "BEGIN EXCLUSIVE", nullptr, nullptr, nullptr), SQLITE_OK);
    try {
      h::record_run(path, rig::test::fixture_passport("LOCKED-2"), d.path.string());
      ADD_FAILURE() << "no exception";
    } catch (const std::exception& e) {  // who holds it, not SQLite's bare "database is locked" (a review)
      EXPECT_NE(std::string(e.what()).find(": locked by another process (a write or a backup holding it): gave up "
                                           "waiting to read it; try again once it is done"),
                std::string::npos)
          << e.what();
      EXPECT_EQ(std::string(e.what()).find('\''), std::string::npos) << e.what();
    }
    // A wait told once it has lasted a second, with the database and its limit.
    std::vector<std::pair<std::string, int>> told;
    h::set_lock_wait_notice([&told](const std::string& where, int limit_ms) { told.emplace_back(where, limit_ms); });
    h::set_lock_wait_ms(1200);  // a wait past a second says how long
    try {
      h::record_run(path, rig::test::fixture_passport("LOCKED-2"), d.path.string());
      ADD_FAILURE() << "no exception";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(": locked by another process for more than 1 s (a write"), std::string::npos)
          << e.what();
    }
    h::set_lock_wait_notice(nullptr);
    ASSERT_EQ(told.size(), 1u);
    EXPECT_EQ(told[0].first, "sqlite:" + path);
    EXPECT_EQ(told[0].second, 1200);
    sqlite3_exec(again, "ROLLBACK", nullptr, nullptr, nullptr);
    sqlite3_close(again);
    h::set_lock_wait_ms(10000);
  } catch (...) {
    h::set_lock_wait_ms(10000);
    throw;
  }
  EXPECT_GE(short_wait, 0.25);
  EXPECT_LT(short_wait, 1.4);
  EXPECT_GE(longer_wait, 1.4);
  EXPECT_LT(longer_wait, 8.0);
}

// A stop that comes while a wait for the lock is under way ends it 2 s after it began: the limit
// was fixed when the connection opened, and a SIGTERM in a run's ending waited the whole 10 s (a
// review). Without the stop the same wait runs past 2 s.
TEST(HistorySqlite, AStopEndsAWaitForTheLockUnderWay) {
  TempDir d;
  const std::string path = (d.path / "h.sqlite").string();
  sqlite3* holder = recorded_and_held(path, d);
  std::atomic<bool> stopped{false};
  h::set_lock_wait_stop([&stopped] { return stopped.load(); });
  std::thread stop([&stopped] {
    std::this_thread::sleep_for(std::chrono::milliseconds(2600));  // past the 2 s: it ends at once then
    stopped = true;
  });
  const double waited = seconds_to_give_up(path, "LOCKED-3", d);
  stop.join();
  const double waited_stopped = seconds_to_give_up(path, "LOCKED-4", d);  // stopped from the start: 2 s
  h::set_lock_wait_stop(nullptr);
  sqlite3_exec(holder, "ROLLBACK", nullptr, nullptr, nullptr);
  sqlite3_close(holder);
  EXPECT_GE(waited, 2.5);
  EXPECT_LT(waited, 6.0);  // 10 s before
  EXPECT_GE(waited_stopped, 1.9);
  EXPECT_LT(waited_stopped, 4.0);
}

TEST(HistorySqlite, PlainPathIsAnSqliteFile) {
  TempDir d;
  const std::string path = (d.path / "h.db").string();
  h::record_run(path, rig::test::fixture_passport(), d.path.string());
  EXPECT_EQ(raw_scalar(path, "SELECT serial FROM runs"), "QA-0042");
  EXPECT_EQ(raw_scalar(path, "SELECT COUNT(*) FROM run_values"), "16");
  EXPECT_EQ(raw_scalar(path, "SELECT MAX(version) FROM schema_version"), std::to_string(h::current_schema_version()));
}

// Version 1 as released (frozen copy of its DDL): runs + run_values, no captures table.
constexpr const char* kSchemaV1 = R"SQL(
CREATE TABLE schema_version (version INTEGER NOT NULL PRIMARY KEY, applied TEXT NOT NULL);
INSERT INTO schema_version VALUES (1, '2026-10-01T00:00:00Z');
CREATE TABLE runs (id INTEGER PRIMARY KEY AUTOINCREMENT, serial TEXT NOT NULL, profile TEXT, plant TEXT, software TEXT,
  started TEXT, finished TEXT, outcome TEXT NOT NULL, run_dir TEXT NOT NULL, passport TEXT NOT NULL);
CREATE UNIQUE INDEX runs_dir_started ON runs (run_dir, started);
CREATE INDEX runs_serial_started ON runs (serial, started);
CREATE TABLE run_values (run_id BIGINT NOT NULL REFERENCES runs (id) ON DELETE CASCADE, name TEXT NOT NULL,
  value DOUBLE PRECISION, unit TEXT, lo DOUBLE PRECISION, hi DOUBLE PRECISION, limit_min DOUBLE PRECISION,
  limit_max DOUBLE PRECISION, outcome TEXT, reason TEXT, PRIMARY KEY (run_id, name));
)SQL";

TEST(HistorySqlite, MigratesAVersion1DatabaseAndBackfillsCaptures) {
  TempDir d;
  const std::string path = (d.path / "old.sqlite").string();
  raw_sql(path, kSchemaV1);
  json p = rig::test::fixture_passport("OLD-1", "ABORTED", "2026-10-02T10:00:00Z");
  p["aborted_reason"] = "operator's Ctrl-C";
  std::string pj = p.dump();
  for (std::size_t i = 0; (i = pj.find('\'', i)) != std::string::npos; i += 2) pj.insert(i, "'");  // SQL quoting
  raw_sql(path, "INSERT INTO runs (serial, profile, plant, software, started, finished, outcome, run_dir, passport) "
                "VALUES ('OLD-1', 'paper', 'hardware', 'rig 0.0.9', '2026-10-02T10:00:00Z', NULL, 'ABORTED', "
                "'/runs/old1', '" + pj + "');"
                "INSERT INTO run_values (run_id, name, value, unit) VALUES (1, 'bias', -5e-4, 'g');");

  EXPECT_EQ(h::migrate(path), 1);  // found version 1, migrated to the current one
  EXPECT_EQ(raw_scalar(path, "SELECT MAX(version) FROM schema_version"), std::to_string(h::current_schema_version()));
  const auto runs = h::list_runs(path, {});
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].software, "rig 0.0.9");
  EXPECT_EQ(runs[0].aborted_reason, "operator's Ctrl-C");  // backfilled from the stored passport
  EXPECT_EQ(runs[0].captures.size(), 3u);
  EXPECT_EQ(runs[0].captures[2], "captures/in-run-U10.cap");
  const auto bias = h::trend(path, "bias", {});
  ASSERT_EQ(bias.size(), 1u);
  EXPECT_DOUBLE_EQ(*bias[0].value, -5e-4);
  // New runs go in next to the old one.
  h::record_run(path, rig::test::fixture_passport("NEW-1"), d.path.string());
  EXPECT_EQ(h::list_runs(path, {}).size(), 2u);
  EXPECT_EQ(h::migrate(path), h::current_schema_version());  // idempotent
}

TEST(HistorySqlite, RefusesASchemaNewerThanThisBuild) {
  TempDir d;
  const std::string path = (d.path / "new.sqlite").string();
  h::migrate(path);
  raw_sql(path, "INSERT INTO schema_version VALUES (99, '2030-01-01T00:00:00Z')");
  try {
    h::list_runs(path, {});
    FAIL() << "no exception";
  } catch (const rig::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("99"), std::string::npos) << e.what();
  }
}

TEST(HistorySqlite, BadUrlsAndUnwritablePlacesNameTheDatabase) {
  TempDir d;
  EXPECT_THROW(h::migrate("mysql://host/db"), rig::ConfigError);
  EXPECT_THROW(h::migrate("postgresql:dbname=x"), rig::ConfigError);
  EXPECT_THROW(h::migrate("sqlite:"), rig::ConfigError);
  rig::test::write_file(d.path / "file", "x");
  try {
    h::migrate("sqlite:" + (d.path / "file" / "sub" / "h.sqlite").string());  // a file where a folder must be
    FAIL() << "no exception";
  } catch (const rig::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("file/sub"), std::string::npos) << e.what();
  }
  rig::test::write_file(d.path / "garbage.sqlite", std::string(4096, 'x'));
  EXPECT_THROW(h::migrate((d.path / "garbage.sqlite").string()), rig::ConfigError);
  // Said as what it is, to read or to record into: no SQL cut off mid-quote (a technician's review).
  for (const bool reading : {true, false}) {
    try {
      if (reading) h::list_runs((d.path / "garbage.sqlite").string(), {});
      else h::migrate((d.path / "garbage.sqlite").string());
      ADD_FAILURE() << "no exception";
    } catch (const rig::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("garbage.sqlite: not an SQLite database (file is not a database)"),
                std::string::npos)
          << e.what();
      EXPECT_EQ(std::string(e.what()).find("SELECT"), std::string::npos) << e.what();
    }
  }
  // A folder in the database's place, to read or to record into (SQLite said "disk I/O error").
  for (const bool reading : {true, false}) {
    try {
      if (reading) h::list_runs("sqlite:" + d.path.string(), {});
      else h::migrate("sqlite:" + d.path.string());
      ADD_FAILURE() << "no exception";
    } catch (const rig::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(": a folder, not a history database file (give the file's path"),
                std::string::npos)
          << e.what();
    }
  }
}

// A mistyped --db must not leave an empty database behind: reading opens read-only.
TEST(HistorySqlite, ReadingNeverCreatesADatabase) {
  TempDir d;
  const fs::path missing = d.path / "sub" / "typo.sqlite";
  const std::string url = "sqlite:" + missing.string();
  for (int which = 0; which < 3; ++which) {
    try {
      if (which == 0) h::list_runs(url, {});
      if (which == 1) h::trend(url, "bias", {});
      if (which == 2) h::value_names(url);
      FAIL() << "no exception for reader " << which;
    } catch (const rig::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("typo.sqlite: no such history database"), std::string::npos) << e.what();
    }
  }
  EXPECT_FALSE(fs::exists(missing));
  EXPECT_FALSE(fs::exists(missing.parent_path())) << "not even its folder";
  // An existing file that is not a rig history is refused, and left as it was.
  rig::test::write_file(d.path / "empty.sqlite", "");
  EXPECT_THROW(h::list_runs((d.path / "empty.sqlite").string(), {}), rig::ConfigError);
  EXPECT_EQ(fs::file_size(d.path / "empty.sqlite"), 0u);
  // A current database is read without being written.
  const std::string good = (d.path / "good.sqlite").string();
  h::record_run(good, rig::test::fixture_passport("RO-1"), d.path.string());
  const auto before = fs::last_write_time(good);
  const auto size = fs::file_size(good);
  EXPECT_EQ(h::list_runs(good, {}).size(), 1u);
  EXPECT_EQ(fs::last_write_time(good), before);
  EXPECT_EQ(fs::file_size(good), size);
}

// A writer killed mid-commit (a run's ending, `rig history --record`) leaves a hot journal that
// only a connection that can write rolls back: a reader that opened the file read-only failed
// with "attempt to write a readonly database", and so did every `rig run` after it (its history
// check), until something else opened the file (a review). Readers open it read-write, held to
// reading: the journal is rolled back and nothing is lost.
TEST(HistorySqlite, AJournalAWriterKilledMidCommitLeftIsRolledBackByTheNextReader) {
  TempDir d;
  const std::string file = (d.path / "h.sqlite").string();
  for (int i = 0; i < 3; ++i)
    h::record_run(file, rig::test::fixture_passport("HOT-" + std::to_string(i)), (d.path / std::to_string(i)).string());
  const std::size_t values = h::trend(file, "bias", {}).size();
  ASSERT_GT(values, 0u);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // a writer that dies with its transaction spilled to the file
    sqlite3* db = nullptr;
    if (sqlite3_open(file.c_str(), &db) != SQLITE_OK) ::_exit(1);
    sqlite3_exec(db, "PRAGMA cache_size = 1; BEGIN IMMEDIATE; DELETE FROM run_values; DELETE FROM runs;", nullptr,
                 nullptr, nullptr);
    ::_exit(0);  // no commit, no rollback, no close
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  ASSERT_TRUE(fs::exists(file + "-journal")) << "the kill left its journal";
  EXPECT_EQ(h::list_runs(file, {}).size(), 3u);
  EXPECT_EQ(h::trend(file, "bias", {}).size(), values);
  EXPECT_FALSE(fs::exists(file + "-journal")) << "rolled back by the reader";
  // Read-write, yet held to reading: a reader's statement cannot change the file.
  const auto db = rig::history::open_db("sqlite:" + file, rig::history::Access::ReadOnly);
  EXPECT_THROW(db->query("DELETE FROM runs", {}), rig::ConfigError);
  EXPECT_EQ(h::list_runs(file, {}).size(), 3u);
}

TEST(HistorySqlite, ConcurrentWritersAllLand) {
  TempDir d;
  const std::string url = "sqlite:" + (d.path / "c.sqlite").string();
  std::vector<std::thread> ts;
  for (int t = 0; t < 3; ++t)
    ts.emplace_back([&, t] {
      for (int i = 0; i < 8; ++i) {
        char started[32];
        std::snprintf(started, sizeof started, "2026-11-%02dT%02d:00:00Z", t + 1, i);
        h::record_run(url, rig::test::fixture_passport("T" + std::to_string(t), "PASS", started),
                      (d.path / ("t" + std::to_string(t))).string());
      }
    });
  for (auto& t : ts) t.join();
  EXPECT_EQ(h::list_runs(url, {}).size(), 24u);
}

// A URL in a message or in run.json never carries its password: libpq's user:pass@ and its
// ?password= parameter alike (a code review: the parameter went into run.json in clear).
TEST(HistoryUrl, ThePasswordIsMaskedWhereverTheUrlCarriesIt) {
  using h::mask_password;
  EXPECT_EQ(mask_password("postgresql://u:secret@h/x"), "postgresql://u:***@h/x");
  EXPECT_EQ(mask_password("postgresql://h/x?password=secret"), "postgresql://h/x?password=***");
  EXPECT_EQ(mask_password("postgresql://u@h/x?sslmode=require&password=s3&connect_timeout=5"),
            "postgresql://u@h/x?sslmode=require&password=***&connect_timeout=5");
  EXPECT_EQ(mask_password("postgresql://h/x?application_password=k"), "postgresql://h/x?application_password=k");
  EXPECT_EQ(mask_password("sqlite:/var/lib/rig/h.sqlite"), "sqlite:/var/lib/rig/h.sqlite");
  EXPECT_EQ(mask_password(mask_password("postgresql://u:p@h/x?password=q")), "postgresql://u:***@h/x?password=***");
}

// One database however its URL was written (run.json's, a resume's, `rig history --record`'s):
// run.json keeps the SQLite file absolute and a server's password masked, and a masked URL is
// known as one (it cannot be opened as it is).
TEST(HistoryUrl, OneDatabaseIsKnownHoweverItsUrlIsWritten) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(testing::TempDir()) / "same-database";
  fs::create_directories(dir / "sub");
  const std::string file = (dir / "h.sqlite").string();
  EXPECT_EQ(h::kept_form("sqlite:" + (dir / "sub" / ".." / "h.sqlite").string()), "sqlite:" + file);
  EXPECT_EQ(h::kept_form("postgresql://u:secret@h/x"), "postgresql://u:***@h/x");
  EXPECT_TRUE(h::same_database(file, "sqlite:" + file));
  EXPECT_TRUE(h::same_database("sqlite://" + file, "sqlite:" + (dir / "sub" / ".." / "h.sqlite").string()));
  std::error_code ec;
  fs::create_symlink(dir, dir / "link", ec);
  if (!ec) {
    EXPECT_TRUE(h::same_database(file, (dir / "link" / "h.sqlite").string()));
  }
  EXPECT_FALSE(h::same_database(file, (dir / "sub" / "h.sqlite").string()));
  EXPECT_TRUE(h::same_database("postgresql://u:secret@h/x", "postgresql://u:***@h/x"));
  EXPECT_FALSE(h::same_database("postgresql://u:secret@h/x", "postgresql://u:secret@h/y"));
  EXPECT_FALSE(h::same_database("postgresql://u@h/x", "sqlite:" + file));
  EXPECT_TRUE(h::password_masked("postgresql://u:***@h/x"));
  EXPECT_TRUE(h::password_masked("postgresql://h/x?password=***"));
  EXPECT_FALSE(h::password_masked("postgresql://u:secret@h/x"));
  EXPECT_FALSE(h::password_masked("sqlite:" + file));
}

TEST(HistoryTime, Iso8601IsNormalisedToUtc) {
  using h::normalize_iso8601;
  EXPECT_EQ(normalize_iso8601("2026-11-22"), "2026-11-22T00:00:00Z");
  EXPECT_EQ(normalize_iso8601(" 2026-11-22T05:12 "), "2026-11-22T05:12:00Z");
  EXPECT_EQ(normalize_iso8601("2026-11-22 05:12:26.123Z"), "2026-11-22T05:12:26Z");
  EXPECT_EQ(normalize_iso8601("2026-11-22T02:12:26+03:00"), "2026-11-21T23:12:26Z");
  EXPECT_EQ(normalize_iso8601("2026-11-21T23:30:00-0130"), "2026-11-22T01:00:00Z");
  EXPECT_EQ(normalize_iso8601("2026-12-31T23:59:59-01:00"), "2027-01-01T00:59:59Z");
  for (const char* bad : {"", "yesterday", "2026-13-01", "2026-11-22T25:00", "2026-11-22T05", "2026-11-22Tx",
                          "2026-11-22T05:12:26+3", "2026-11-22 junk", "26-11-22", "2026-02-30", "2026-02-29",
                          "2100-02-29", "2026-04-31", "2026-11-31T00:00"})
    EXPECT_FALSE(normalize_iso8601(bad).has_value()) << bad;
  EXPECT_EQ(normalize_iso8601("2028-02-29"), "2028-02-29T00:00:00Z");  // leap years
  EXPECT_EQ(normalize_iso8601("2000-02-29"), "2000-02-29T00:00:00Z");
}

// ---------------------------------------------------------------- default location
struct EnvGuard {
  std::vector<std::pair<std::string, std::optional<std::string>>> saved;
  void set(const char* k, const char* v) {
    const char* old = std::getenv(k);
    saved.emplace_back(k, old ? std::optional<std::string>(old) : std::nullopt);
    if (v) setenv(k, v, 1);
    else unsetenv(k);
  }
  ~EnvGuard() {
    for (auto it = saved.rbegin(); it != saved.rend(); ++it) {
      if (it->second) setenv(it->first.c_str(), it->second->c_str(), 1);
      else unsetenv(it->first.c_str());
    }
  }
};

TEST(HistoryDefaultUrl, EnvironmentThenConfigThenXdgThenHome) {
  TempDir d;
  EnvGuard env;
  env.set("RIG_HISTORY", nullptr);
  env.set("RIG_CONFIG", nullptr);
  env.set("XDG_DATA_HOME", nullptr);
  env.set("HOME", d.path.c_str());
  EXPECT_EQ(h::default_db_url(), "sqlite:" + (d.path / ".local/share/rig/history.sqlite").string());
  env.set("XDG_DATA_HOME", (d.path / "xdg").c_str());
  EXPECT_EQ(h::default_db_url(), "sqlite:" + (d.path / "xdg/rig/history.sqlite").string());
  // ~/.config/rig/rig.toml with a relative path: relative to the config's folder.
  rig::test::write_file(d.path / ".config/rig/rig.toml", "[history]\nurl = \"sqlite:results/h.sqlite\"\n");
  EXPECT_EQ(h::default_db_url(), "sqlite:" + (d.path / ".config/rig/results/h.sqlite").string());
  // "~/" is the home folder, as a shell would read it (no shell expands it inside a file).
  rig::test::write_file(d.path / ".config/rig/rig.toml", "[history]\nurl = \"sqlite:~/line/h.sqlite\"\n");
  EXPECT_EQ(h::default_db_url(), "sqlite:" + (d.path / "line/h.sqlite").string());
  rig::test::write_file(d.path / ".config/rig/rig.toml", "[history]\nurl = \"mysql://db/x\"\n");
  try {
    h::default_db_url();
    ADD_FAILURE() << "no exception";
  } catch (const rig::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("rig.toml:2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("unknown scheme"), std::string::npos) << e.what();
  }
  rig::test::write_file(d.path / "tilde.toml", "[history]\nurl = \"sqlite:~/h.sqlite\"\n");
  env.set("RIG_CONFIG", (d.path / "tilde.toml").c_str());
  env.set("HOME", nullptr);
  try {
    h::default_db_url();
    ADD_FAILURE() << "no exception";
  } catch (const rig::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("tilde.toml:2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("$HOME is not set"), std::string::npos) << e.what();
  }
  env.set("HOME", d.path.c_str());
  env.set("RIG_CONFIG", nullptr);
  // $RIG_CONFIG wins over the home config; a PostgreSQL URL is kept as is.
  rig::test::write_file(d.path / "line.toml", "[other]\nx = 1\n[history]\nurl = \"postgresql://rig@db.line/results\"\n");
  env.set("RIG_CONFIG", (d.path / "line.toml").c_str());
  EXPECT_EQ(h::default_db_url(), "postgresql://rig@db.line/results");
  // Set but empty is said, not read as unset (an empty RIG_SEAL_KEY is refused likewise).
  env.set("RIG_HISTORY", "");
  EXPECT_THROW(
      {
        try {
          h::default_db_url();
        } catch (const rig::ConfigError& e) {
          EXPECT_NE(std::string(e.what()).find("RIG_HISTORY is set but empty"), std::string::npos) << e.what();
          throw;
        }
      },
      rig::ConfigError);
  env.set("RIG_HISTORY", nullptr);
  env.set("RIG_CONFIG", "");
  EXPECT_THROW(h::default_db_url(), rig::ConfigError);
  env.set("RIG_CONFIG", (d.path / "line.toml").c_str());
  // $RIG_HISTORY wins over everything.
  env.set("RIG_HISTORY", "sqlite:/tmp/x.sqlite");
  EXPECT_EQ(h::default_db_url(), "sqlite:/tmp/x.sqlite");
  // Blanks at an end are a quoting slip: RIG_HISTORY=' ' or --db ' ' opened a file named " " in
  // the working folder (a review).
  for (const char* url : {" ", "\t", "sqlite: ", " /tmp/h.sqlite", "/tmp/h.sqlite "}) {
    try {
      h::sqlite_path(url);
      ADD_FAILURE() << "taken: '" << url << "'";
    } catch (const rig::ConfigError& e) {
      const std::string w = e.what();
      EXPECT_TRUE(w.find("is blank") != std::string::npos || w.find("begins or ends with a blank") != std::string::npos ||
                  w.find("names no file") != std::string::npos)
          << w;
    }
  }
}

// "sqlite:~/x" in --db or $RIG_HISTORY made a folder named "~" in the working folder (a review).
TEST(HistorySqlite, ATildeIsTheHomeFolder) {
  TempDir d;
  EnvGuard env;
  env.set("HOME", (d.path / "home").c_str());
  h::migrate("sqlite:~/results/h.sqlite");
  EXPECT_TRUE(fs::exists(d.path / "home/results/h.sqlite"));
  EXPECT_EQ(h::sqlite_path("~/h.sqlite"), (d.path / "home/h.sqlite").string());
  EXPECT_EQ(h::sqlite_path("sqlite:~user/h.sqlite"), "~user/h.sqlite") << "only the user's own ~";
  env.set("HOME", nullptr);
  EXPECT_THROW(h::sqlite_path("sqlite:~/h.sqlite"), rig::ConfigError);
}

// One answer for the run's checks, its dry run and its "a new database" note.
TEST(HistorySqlite, TheFileIsLookedAtAsItIsNow) {
  TempDir d;
  const std::string there = (d.path / "h.sqlite").string(), folder = (d.path / "new/deeper").string();
  EXPECT_FALSE(h::sqlite_file("postgresql://rig@db.line/results").has_value());
  auto f = h::sqlite_file("sqlite:" + there);
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->path, there);
  EXPECT_FALSE(f->exists);
  EXPECT_EQ(f->missing_folder, "") << "its folder is there";
  rig::test::write_file(there, "");
  EXPECT_TRUE(h::sqlite_file(there)->exists);
  f = h::sqlite_file("sqlite:" + folder + "/h.sqlite");
  EXPECT_FALSE(f->exists);
  EXPECT_EQ(f->missing_folder, folder);
  EXPECT_THROW(h::sqlite_file("mysql://x/y"), rig::ConfigError);
}

TEST(HistoryDefaultUrl, ConfigMistakesNameFileAndLine) {
  TempDir d;
  EnvGuard env;
  env.set("RIG_HISTORY", nullptr);
  rig::test::write_file(d.path / "bad.toml", "[history]\nurll = \"x\"\n");
  env.set("RIG_CONFIG", (d.path / "bad.toml").c_str());
  try {
    h::default_db_url();
    FAIL() << "no exception";
  } catch (const rig::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.toml:2"), std::string::npos) << e.what();
  }
  env.set("RIG_CONFIG", (d.path / "missing.toml").c_str());
  EXPECT_THROW(h::default_db_url(), rig::ConfigError);
}

// ---------------------------------------------------------------- `rig history`
// Environment variables set (or, nullopt, unset) for a scope, restored after it.
class Env {
 public:
  Env(std::initializer_list<std::pair<std::string, std::optional<std::string>>> vars) {
    for (const auto& [name, value] : vars) {
      const char* old = std::getenv(name.c_str());
      saved_.emplace_back(name, old ? std::optional<std::string>(old) : std::nullopt);
      if (value) ::setenv(name.c_str(), value->c_str(), 1);
      else ::unsetenv(name.c_str());
    }
  }
  ~Env() {
    for (const auto& [name, value] : saved_) {
      if (value) ::setenv(name.c_str(), value->c_str(), 1);
      else ::unsetenv(name.c_str());
    }
  }
  Env(const Env&) = delete;
  Env& operator=(const Env&) = delete;

 private:
  std::vector<std::pair<std::string, std::optional<std::string>>> saved_;
};

std::string run_cli(std::vector<std::string> args) {
  CLI::App app;
  int rc = -1;
  rig::cli::add_history(app, rc);
  args.insert(args.begin(), "history");
  std::reverse(args.begin(), args.end());  // CLI11 takes the arguments reversed
  testing::internal::CaptureStdout();
  try {
    app.parse(args);
  } catch (...) {
    testing::internal::GetCapturedStdout();
    throw;
  }
  EXPECT_EQ(rc, rig::kExitPass);
  return testing::internal::GetCapturedStdout();
}

std::vector<std::string> lines(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

TEST(HistoryCli, ListsTrendsAndWritesCsv) {
  TempDir d;
  const std::string db = "sqlite:" + (d.path / "h.sqlite").string();
  const json a = rig::test::fixture_analysis();
  rig::test::write_run(d.path / "r1", rig::test::fixture_passport("SN,1", "PASS", "2026-11-01T08:00:00Z"), &a);
  EXPECT_NE(run_cli({"--db", db, "--record", (d.path / "r1").string()}).find("recorded run"), std::string::npos);
  json p2 = rig::test::fixture_passport("SN-2", "FAIL", "2026-11-02T08:00:00Z");
  p2["values"]["bias"]["value"] = -6.0e-4;
  h::record_run(db, p2, (d.path / "r2").string());

  const auto list = lines(run_cli({"--db", db}));
  ASSERT_EQ(list.size(), 3u);
  EXPECT_EQ(list[0].rfind("id", 0), 0u);
  EXPECT_NE(list[1].find("SN,1"), std::string::npos);
  EXPECT_NE(list[2].find("FAIL"), std::string::npos);

  const auto csv = lines(run_cli({"--db", db, "--csv"}));
  ASSERT_EQ(csv.size(), 3u);
  EXPECT_EQ(csv[0], "id,started,serial,profile,plant,outcome,station,software,run_dir,captures,earlier\r");
  EXPECT_NE(csv[1].find(",\"SN,1\",paper,"), std::string::npos) << csv[1];  // RFC 4180 quoting
  EXPECT_NE(csv[1].find("captures/run01-U10.cap;captures/run02-U20.cap;captures/in-run-U10.cap,\r"), std::string::npos)
      << csv[1];  // no earlier ending

  // r2 put back and resumed to an ABORTED ending: the FAIL stays among its endings, said so.
  json back = p2;
  back["outcome"] = "ABORTED";
  back["aborted_reason"] = "SIGINT";
  back["finished"] = "2026-11-02T09:00:00Z";
  const h::Recorded again = h::record_run(db, back, (d.path / "r2").string());
  ASSERT_TRUE(again.replaced_verdict);
  const auto csv2 = lines(run_cli({"--db", db, "--csv", "--serial", "SN-2"}));
  ASSERT_EQ(csv2.size(), 2u);
  EXPECT_NE(csv2[1].find(",ABORTED,"), std::string::npos) << csv2[1];
  EXPECT_EQ(csv2[1].substr(csv2[1].size() - 6), ",FAIL\r") << csv2[1];
  const auto ends = lines(run_cli({"--db", db, "--endings", std::to_string(again.id)}));
  ASSERT_EQ(ends.size(), 4u);
  EXPECT_EQ(ends[0], "run " + std::to_string(again.id) + ": 2 ending(s), in the order recorded");
  EXPECT_NE(ends[2].find("FAIL"), std::string::npos);
  EXPECT_NE(ends[3].find("ABORTED  SIGINT"), std::string::npos) << ends[3];
  const auto ends_csv = lines(run_cli({"--db", db, "--endings", std::to_string(again.id), "--csv"}));
  ASSERT_EQ(ends_csv.size(), 3u);
  EXPECT_EQ(ends_csv[0], "run_id,seq,recorded,finished,outcome,aborted_reason\r");
  EXPECT_THROW(run_cli({"--db", db, "--endings", "99"}), rig::ConfigError);
  EXPECT_THROW(run_cli({"--db", db, "--endings", "0"}), CLI::ValidationError);
  EXPECT_THROW(run_cli({"--db", db, "--endings", "1", "--serial", "SN-2"}), CLI::ExcludesError);
  h::record_run(db, p2, (d.path / "r2").string());  // its FAIL again, for the trend below

  const auto trend = lines(run_cli({"--db", db, "--value", "bias", "--csv"}));
  ASSERT_EQ(trend.size(), 3u);
  EXPECT_EQ(trend[0].rfind("run_id,started,serial,run_outcome,name,value,unit", 0), 0u);
  EXPECT_NE(trend[1].find(",-0.00050137000000000001,g,"), std::string::npos) << trend[1];  // every digit
  EXPECT_NE(trend[2].find(",-0.00059999999999999995,g,"), std::string::npos) << trend[2];

  const std::string text = run_cli({"--db", db, "--value", "bias"});
  EXPECT_NE(text.find("bias over 2 run(s)"), std::string::npos);
  EXPECT_NE(text.find("all DUTs"), std::string::npos);  // across DUTs
  EXPECT_NE(text.find("-0.000550685"), std::string::npos) << text;  // their mean

  const auto one = lines(run_cli({"--db", db, "--serial", "SN-2", "--since", "2026-11-02", "--csv"}));
  EXPECT_EQ(one.size(), 2u);
  // A bound with a fraction of a second compares with the whole-second times as the instant it is
  // (a review: it was cut to the second, so --until ...:00.9 left out the run started at :00).
  EXPECT_EQ(lines(run_cli({"--db", db, "--until", "2026-11-02T08:00:00.9Z", "--csv"})).size(), 3u);
  EXPECT_EQ(lines(run_cli({"--db", db, "--until", "2026-11-02T08:00:00.000Z", "--csv"})).size(), 2u);
  EXPECT_EQ(lines(run_cli({"--db", db, "--since", "2026-11-02T08:00:00.9Z", "--csv"})).size(), 1u);  // the header
  EXPECT_EQ(lines(run_cli({"--db", db, "--since", "2026-11-02T08:00:00.0Z", "--csv"})).size(), 2u);
  EXPECT_NE(run_cli({"--db", db, "--serial", "nobody"}).find("no runs recorded match"), std::string::npos);
  // --outcome in any case (a review: `--outcome pass` was refused); a bad date is the option's
  // mistake, not the database's, whichever names it (it read "RIG_HISTORY: --since ...").
  EXPECT_EQ(lines(run_cli({"--db", db, "--outcome", "fail", "--csv"})).size(), 2u);
  ::setenv("RIG_HISTORY", db.c_str(), 1);
  try {
    run_cli({"--since", "2026-13-01"});
    ADD_FAILURE() << "no exception";
  } catch (const rig::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--since '2026-13-01' is not an ISO 8601 date", 0), 0u) << e.what();
  }
  ::unsetenv("RIG_HISTORY");
  try {
    run_cli({"--db", db, "--value", "biass"});
    FAIL() << "no exception";
  } catch (const rig::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("recorded: "), std::string::npos) << e.what();
  }
  EXPECT_THROW(run_cli({"--db", db, "--record", (d.path / "none").string()}), rig::ConfigError);
  // A query option beside --record is a usage error, not ignored (a review: --serial OTHER recorded
  // the folder whatever its serial).
  for (const std::vector<std::string>& extra :
       {std::vector<std::string>{"--serial", "OTHER"}, {"--csv"}, {"--value", "bias"}, {"--limit", "1"}}) {
    std::vector<std::string> args = {"--db", db, "--record", (d.path / "r1").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    EXPECT_THROW(run_cli(args), CLI::ExcludesError) << extra[0];
  }
  // A passport edited after its run (the FAIL of a value outside its limits made PASS) is not history.
  json edited = rig::test::fixture_passport("SN-3", "PASS", "2026-11-03T08:00:00Z");
  edited["values"]["bias"]["value"] = -6.0e-3;
  rig::test::write_run(d.path / "r3", edited, &a);
  try {
    run_cli({"--db", db, "--record", (d.path / "r3").string()});
    ADD_FAILURE() << "recorded an edited passport";
  } catch (const rig::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("values.bias.outcome is PASS, but its value -0.006 is outside"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(lines(run_cli({"--db", db})).size(), 3u);  // still the two runs
}

TEST(HistoryCli, AMissingDbIsAnErrorAndTheDefaultOneIsNotCreated) {
  TempDir d;
  const fs::path typo = d.path / "histroy.sqlite";
  EXPECT_THROW(run_cli({"--db", "sqlite:" + typo.string()}), rig::ConfigError);
  EXPECT_THROW(run_cli({"--db", typo.string(), "--value", "bias"}), rig::ConfigError);
  EXPECT_FALSE(fs::exists(typo));
  // The built-in default exists only once a run has been recorded: "no runs recorded yet". A
  // database $RIG_HISTORY or the rig config names is a choice, and one that is not there is an
  // error (a typo there looked like an empty history, a review).
  const fs::path dflt = d.path / "data" / "rig" / "history.sqlite";
  {
    const Env env{{"XDG_DATA_HOME", (d.path / "data").string()}, {"HOME", d.path.string()},
                  {"RIG_HISTORY", std::nullopt}, {"RIG_CONFIG", std::nullopt}};
    const std::string out = run_cli({});
    EXPECT_NE(out.find("no runs recorded yet (sqlite:" + dflt.string() + " does not exist)"), std::string::npos) << out;
  }
  EXPECT_FALSE(fs::exists(dflt));
  {
    const Env env{{"RIG_HISTORY", "sqlite:" + typo.string()}};
    try {
      run_cli({});
      ADD_FAILURE() << "a missing database $RIG_HISTORY names read as an empty history";
    } catch (const rig::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("RIG_HISTORY: sqlite:" + typo.string() + ": no such history database"),
                std::string::npos)
          << e.what();
    }
  }
  std::ofstream(d.path / "rig.toml") << "[history]\nurl = \"sqlite:histroy.sqlite\"\n";
  {
    const Env env{{"RIG_HISTORY", std::nullopt}, {"RIG_CONFIG", (d.path / "rig.toml").string()}};
    try {
      run_cli({"--value", "bias"});
      ADD_FAILURE() << "a missing database the rig config names read as an empty history";
    } catch (const rig::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(typo.string() + ": no such history database (reading never creates one; "
                                                           "check --db, $RIG_HISTORY or the rig config's [history] url)"),
                std::string::npos)
          << e.what();
    }
  }
  EXPECT_FALSE(fs::exists(typo));
}

// `--value` statistics: per DUT and unit (a run that wrote bias in mg was averaged with runs in g,
// a review), `runs` beside `n` (a DUT whose values are all null was left out), the run's outcome
// in the listing, and columns padded by characters (a Cyrillic serial shifted every column).
TEST(HistoryCli, StatisticsArePerDutAndUnitAndCountEveryRun) {
  TempDir d;
  const std::string db = "sqlite:" + (d.path / "h.sqlite").string();
  h::record_run(db, rig::test::fixture_passport("SN-A", "PASS", "2026-11-01T08:00:00Z"), (d.path / "a1").string());
  json mg = rig::test::fixture_passport("SN-A", "PASS", "2026-11-02T08:00:00Z");
  mg["values"]["bias"]["value"] = -0.5;
  mg["values"]["bias"]["unit"] = "mg";
  mg["values"]["bias"]["limits"] = {-1, 1};
  h::record_run(db, mg, (d.path / "a2").string());
  json aborted = rig::test::fixture_passport("ДУТ-Ü7", "ABORTED", "2026-11-03T08:00:00Z");
  aborted["values"]["bias"]["value"] = nullptr;
  aborted["values"]["bias"]["outcome"] = "UNSET";
  h::record_run(db, aborted, (d.path / "u1").string());
  const auto out = lines(run_cli({"--db", db, "--value", "bias"}));
  const auto has = [&](const std::string& text) {
    return std::any_of(out.begin(), out.end(), [&](const std::string& l) { return l.find(text) != std::string::npos; });
  };
  EXPECT_TRUE(has("note: bias was recorded in 2 units; each unit has its own statistics"));
  EXPECT_TRUE(has("SN-A      g     paper    1     1  -0.00050137  -   -0.00050137  -0.00050137  0"));
  EXPECT_TRUE(has("SN-A      mg    paper    1     1  -0.5         -   -0.5         -0.5         0"));
  EXPECT_TRUE(has("ДУТ-Ü7    g     paper    1     0  -            -   -            -            -"));
  EXPECT_TRUE(has("all DUTs  g     paper    2     1  -0.00050137"));
  EXPECT_FALSE(has("all DUTs  mg"));  // one DUT in mg: nothing across DUTs
  EXPECT_FALSE(has("profiles; each profile"));  // one profile
  // A run of another profile (another procedure, other record lengths) has its own statistics,
  // and a note says so: a ci run's bias was averaged with a paper run's (a technician's review).
  json ci = rig::test::fixture_passport("SN-A", "PASS", "2026-11-04T08:00:00Z");
  ci["profile"] = "ci";
  ci["values"]["bias"]["value"] = -0.0006;
  h::record_run(db, ci, (d.path / "a3").string());
  const auto mixed = lines(run_cli({"--db", db, "--value", "bias"}));
  const auto has_mixed = [&](const std::string& text) {
    return std::any_of(mixed.begin(), mixed.end(), [&](const std::string& l) { return l.find(text) != std::string::npos; });
  };
  EXPECT_TRUE(has_mixed("note: bias was measured under 2 profiles; each profile has its own statistics (--profile P for one)"));
  EXPECT_TRUE(has_mixed("SN-A      g     ci       1     1  -0.0006"));
  EXPECT_TRUE(has_mixed("SN-A      g     paper    1     1  -0.00050137"));
  const auto csv = lines(run_cli({"--db", db, "--value", "bias", "--csv"}));
  ASSERT_FALSE(csv.empty());
  EXPECT_EQ(csv[0], "run_id,started,serial,run_outcome,name,value,unit,lo,hi,limit_min,limit_max,outcome,reason,profile\r");
  EXPECT_NE(csv.back().find(",ci\r"), std::string::npos) << csv.back();
  // The listing: the run's outcome in its own column, aligned after the Cyrillic serial (the
  // column's position counted in characters).
  const auto column = [](const std::string& line, const std::string& text) {
    const std::size_t at = line.find(text);
    if (at == std::string::npos) return std::string::npos;
    return static_cast<std::size_t>(std::count_if(line.begin(), line.begin() + static_cast<std::ptrdiff_t>(at),
                                                   [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
  };
  std::size_t header = std::string::npos, row = std::string::npos, latin = std::string::npos;
  for (const std::string& l : out) {
    if (l.rfind("id  started", 0) == 0) header = column(l, "run ");
    if (l.find("ДУТ-Ü7") != std::string::npos && l.find("ABORTED") != std::string::npos) row = column(l, "ABORTED");
    if (l.find("2026-11-01T08:00:00Z  SN-A") != std::string::npos) latin = column(l, "PASS");
  }
  EXPECT_NE(header, std::string::npos);
  EXPECT_EQ(row, header) << "columns padded by characters, not bytes";
  EXPECT_EQ(latin, header);
}

// The text listing shows a folder path's control characters as \xNN, as messages show names (an
// escape sequence in a run folder's name reached the terminal raw: a review); the CSV keeps them.
TEST(HistoryCli, TheListingShowsControlCharactersEscaped) {
  TempDir d;
  const std::string db = "sqlite:" + (d.path / "h.sqlite").string();
  const std::string dir = (d.path / "run\x1b[2Jx").string();
  h::record_run(db, rig::test::fixture_passport("SN-1", "PASS", "2026-11-01T08:00:00Z"), dir);
  const std::string text = run_cli({"--db", db});
  EXPECT_EQ(text.find('\x1b'), std::string::npos) << text;
  EXPECT_NE(text.find("run\\x1B[2Jx"), std::string::npos) << text;
  EXPECT_NE(run_cli({"--db", db, "--csv"}).find("run\x1b[2Jx"), std::string::npos);
}

// `--record` reads a passport as `rig report` does (rig/report/passport_read.hpp): what the report
// refuses is not recorded (a review recorded another schema, a 'values' list, an outcome "PASSED"
// and a start time "yesterday" that sorted as the newest run), and a copy of a recorded folder is
// noted.
TEST(HistoryCli, RecordRefusesWhatTheReportRefusesAndNotesACopy) {
  TempDir d;
  const std::string db = "sqlite:" + (d.path / "h.sqlite").string();
  const json good = rig::test::fixture_passport("SN-1", "PASS", "2026-11-01T08:00:00Z");
  const std::vector<std::pair<std::function<void(json&)>, std::string>> cases = {
      {[](json& p) { p["schema"] = "rig.passport/2"; }, "unsupported passport schema \"rig.passport/2\""},
      {[](json& p) { p["values"] = json::array(); }, "values: an object of measurements, not []"},
      {[](json& p) { p.erase("values"); }, "values: an object of measurements, not absent"},
      {[](json& p) { p["outcome"] = "PASSED"; }, "outcome: PASS, FAIL, ABORTED or ERROR, not \"PASSED\""},
      {[](json& p) { p["started"] = "yesterday"; }, "started: an ISO 8601 time (2026-11-29T17:11:50Z), not \"yesterday\""},
      {[](json& p) { p["serial"] = "a\nb"; }, "serial: a non-empty string without control characters, not \"a\\nb\""},
      {[](json& p) { p["values"]["bias"]["value"] = "-5e-4"; }, "values.bias.value: a number or null, not \"-5e-4\""},
      {[](json& p) { p["values"]["q"]["outcome"] = "FAIL"; },
       "values.q.outcome is FAIL, but it has a value and no limits (not judged: UNSET)"},
      {[](json& p) {
         p["values"]["k"]["value"] = nullptr;
         p["values"]["k"]["outcome"] = "PASS";
       },
       "values.k.outcome is PASS, but it has no value"},
  };
  for (const auto& [edit, message] : cases) {
    json p = good;
    edit(p);
    rig::test::write_run(d.path / "r", p, nullptr);
    try {
      run_cli({"--db", db, "--record", (d.path / "r").string()});
      ADD_FAILURE() << "recorded: " << message;
    } catch (const rig::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find((d.path / "r" / "passport.json").string() + ": " + message), std::string::npos)
          << e.what();
    }
  }
  EXPECT_FALSE(fs::exists(d.path / "h.sqlite")) << "nothing recorded, not even an empty database";
  rig::test::write_run(d.path / "r", good, nullptr);
  run_cli({"--db", db, "--record", (d.path / "r").string()});
  fs::copy(d.path / "r", d.path / "copy", fs::copy_options::recursive);
  testing::internal::CaptureStderr();
  run_cli({"--db", db, "--record", (d.path / "copy").string()});
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("the same run (serial SN-1, started 2026-11-01T08:00:00Z) is also recorded from " +
                     fs::weakly_canonical(d.path / "r").string() + " (run 1): a copy of its folder, or another run of this DUT started in the same second"),
            std::string::npos)
      << err;
}

}  // namespace
