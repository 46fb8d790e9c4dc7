#include "rig/report/db.hpp"

#include <cstring>
#include <libpq-fe.h>
#include <sqlite3.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <iterator>
#include <thread>

#include <charconv>
#include <cstring>
#include <optional>
#include <cstdio>
#include <filesystem>
#include <type_traits>

#include <unistd.h>

#include "rig/core/errors.hpp"
#include "rig/core/lazy_library.hpp"
#include "rig/core/path_kind.hpp"

namespace rig::history {

std::optional<double> as_double(const Value& v) {
  if (const auto* d = std::get_if<double>(&v)) return *d;
  if (const auto* i = std::get_if<int64_t>(&v)) return static_cast<double>(*i);
  if (const auto* s = std::get_if<std::string>(&v)) {
    double d = 0;
    auto [p, ec] = std::from_chars(s->data(), s->data() + s->size(), d);
    if (ec == std::errc() && p == s->data() + s->size()) return d;
  }
  return std::nullopt;
}

std::optional<int64_t> as_int(const Value& v) {
  if (const auto* i = std::get_if<int64_t>(&v)) return *i;
  if (const auto* d = std::get_if<double>(&v)) return static_cast<int64_t>(*d);
  if (const auto* s = std::get_if<std::string>(&v)) {
    int64_t i = 0;
    auto [p, ec] = std::from_chars(s->data(), s->data() + s->size(), i);
    if (ec == std::errc() && p == s->data() + s->size()) return i;
  }
  return std::nullopt;
}

std::string as_text(const Value& v) {
  if (const auto* s = std::get_if<std::string>(&v)) return *s;
  if (const auto* i = std::get_if<int64_t>(&v)) return std::to_string(*i);
  if (const auto* d = std::get_if<double>(&v)) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", *d);
    return buf;
  }
  return "";
}

void Db::rollback() noexcept {
  try {
    exec("ROLLBACK");
  } catch (...) {  // nothing to roll back (connection lost or no transaction): keep the first error
  }
}

namespace {

std::atomic<int> lock_wait_ms{10000};  // set_lock_wait_ms
std::function<bool()> lock_wait_stopped;  // set_lock_wait_stop
std::function<void(const std::string&, int)> lock_wait_notice;  // set_lock_wait_notice

// SQLite's busy handler (in place of sqlite3_busy_timeout, whose limit is fixed when the
// connection opens): retries with SQLite's own back-off, 1 ms growing to 100 ms, until the limit,
// which is read on every retry. `wait` is the connection's.
struct LockWait {
  std::string where;  // the database, for the notice
  std::chrono::steady_clock::time_point since;  // when the current wait began
  bool noticed = false;  // the current wait told (set_lock_wait_notice)
  std::chrono::steady_clock::duration gave_up_after{-1};  // the last wait given up, for its message
};
int wait_for_lock(void* wait_ptr, int count) {
  using Clock = std::chrono::steady_clock;
  auto& wait = *static_cast<LockWait*>(wait_ptr);
  const Clock::time_point now = Clock::now();
  if (count == 0) {
    wait.since = now;
    wait.noticed = false;
  }
  int limit = lock_wait_ms.load();
  if (lock_wait_stopped && lock_wait_stopped()) limit = std::min(limit, kStoppedLockWaitMs);
  const auto left = std::chrono::milliseconds(limit) - (now - wait.since);
  if (!wait.noticed && lock_wait_notice && now - wait.since >= std::chrono::milliseconds(kLockWaitNoticeMs) &&
      left > Clock::duration::zero()) {
    wait.noticed = true;
    lock_wait_notice(wait.where, limit);
  }
  if (left <= Clock::duration::zero()) {
    wait.gave_up_after = now - wait.since;
    return 0;
  }
  static constexpr int kDelays[] = {1, 2, 5, 10, 15, 20, 25, 25, 25, 50, 50, 100};
  const auto delay = std::chrono::milliseconds(kDelays[std::min<std::size_t>(static_cast<std::size_t>(count), std::size(kDelays) - 1)]);
  std::this_thread::sleep_for(std::min<Clock::duration>(delay, left));
  return 1;
}

// ---------------------------------------------------------------- SQLite
// SQLite's message, with the system's reason where one lies under it: a full disk refusing the
// journal reads "unable to open database file" alone (session 65's list), and that reads as a
// missing file, not as the disk to free.
std::string sqlite_said(sqlite3* db) {
  std::string said = sqlite3_errmsg(db);
  // Only for the errors SQLite records it with (it stays from an earlier failure otherwise).
  const int rc = sqlite3_errcode(db);
  if (const int e = sqlite3_system_errno(db); e != 0 && (rc == SQLITE_CANTOPEN || rc == SQLITE_IOERR))
    said += std::string(" (") + std::strerror(e) + ")";
  return said;
}

class SqliteDb final : public Db {
 public:
  SqliteDb(const std::string& path, Access access) {
    where_ = "sqlite:" + path;
    const std::filesystem::path p(path);
    // A folder in its place: SQLite said "disk I/O error" or "unable to open database file" (a review).
    if (path_kind(path, "history database") == PathKind::directory)
      throw ConfigError(where_ + ": a folder, not a history database file (give the file's path, e.g. " +
                        (p / "history.sqlite").string() + ")");
    if (access == Access::ReadOnly) {
      if (path_kind(path, "history database") == PathKind::missing)
        throw ConfigError(where_ + ": no such history database (reading never creates one; check --db, "
                                   "$RIG_HISTORY or the rig config's [history] url)");
    } else if (p.has_parent_path()) {
      std::error_code ec;
      std::filesystem::create_directories(p.parent_path(), ec);
      if (ec) throw ConfigError(where_ + ": cannot create folder " + p.parent_path().string() + ": " + ec.message());
    }
    // A reader that could write opens the file read-write, its statements held to reading
    // (query_only): a journal a writer killed mid-commit left ("hot") is rolled back only by a
    // connection that can write, and opened read-only every reader after such a kill failed with
    // "attempt to write a readonly database", `rig run` included (its history check), until
    // something else opened the file (a review).
    const std::string journal = path + "-journal";
    const std::string folder = p.has_parent_path() ? p.parent_path().string() : std::string(".");
    const bool writable = ::access(path.c_str(), R_OK | W_OK) == 0 && ::access(folder.c_str(), W_OK | X_OK) == 0;
    const bool query_only = access == Access::ReadOnly && writable;
    const int mode = access == Access::ReadOnly ? (writable ? SQLITE_OPEN_READWRITE : SQLITE_OPEN_READONLY)
                                                : SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE;
    if (access == Access::ReadOnly && !writable && path_kind(journal, "history journal") != PathKind::missing)
      throw ConfigError(where_ + ": " + journal + " is left by a write that was interrupted, and only an account "
                        "that may write " + path + " and its folder can roll it back (rig history --record DIR, or "
                        "sqlite3 " + path + " 'PRAGMA integrity_check', run by that account)");
    if (sqlite3_open_v2(path.c_str(), &db_, mode | SQLITE_OPEN_FULLMUTEX, nullptr) != SQLITE_OK) {
      std::string msg = db_ ? sqlite_said(db_) : "out of memory";
      sqlite3_close(db_);
      db_ = nullptr;
      throw ConfigError(where_ + ": cannot open the history database: " + msg);
    }
    // Several rig processes may write one file: wait for a lock instead of failing.
    lock_wait_.where = where_;
    sqlite3_busy_handler(db_, wait_for_lock, &lock_wait_);
    exec("PRAGMA foreign_keys = ON");
    if (query_only) exec("PRAGMA query_only = ON");
  }
  ~SqliteDb() override { sqlite3_close(db_); }

  std::vector<Row> query(const std::string& sql, const std::vector<Value>& params) override {
    sqlite3_stmt* st = nullptr;
    if (sqlite3_prepare_v2(db_, sql.c_str(), static_cast<int>(sql.size()), &st, nullptr) != SQLITE_OK)
      fail("prepare", sql);
    std::unique_ptr<sqlite3_stmt, int (*)(sqlite3_stmt*)> guard(st, sqlite3_finalize);
    for (std::size_t i = 0; i < params.size(); ++i) bind(st, static_cast<int>(i + 1), params[i]);
    std::vector<Row> rows;
    for (;;) {
      const int rc = sqlite3_step(st);
      if (rc == SQLITE_DONE) break;
      if (rc != SQLITE_ROW) fail("run", sql);
      Row r;
      const int n = sqlite3_column_count(st);
      for (int c = 0; c < n; ++c) r.push_back(column(st, c));
      rows.push_back(std::move(r));
    }
    return rows;
  }

  void begin_exclusive() override { exec("BEGIN IMMEDIATE"); }
  std::string backend() const override { return "sqlite"; }
  std::string dialect_type(const std::string& word) const override {
    return word == "id" ? "INTEGER PRIMARY KEY AUTOINCREMENT" : word;
  }
  bool has_table(const std::string& name) override {
    return !query("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?", {name}).empty();
  }

 private:
  // The statement by its kind (a SELECT, an INSERT), not its text cut at 60 characters mid-quote
  // (a review); a file that is no SQLite database said as such.
  [[noreturn]] void fail(const char* what, const std::string& sql) {
    if (sqlite3_errcode(db_) == SQLITE_NOTADB)
      throw ConfigError(where_ + ": not an SQLite database (" + sqlite3_errmsg(db_) +
                        "): give the history's file, or a new file's name for a new history");
    const std::size_t b = sql.find_first_not_of(" \t\n"), e = sql.find_first_of(" \t\n(", b);
    const std::string word = b == std::string::npos ? std::string() : sql.substr(b, e - b);
    const std::string kind = word.empty() ? std::string("a") : (std::strchr("AEIOUaeiou", word[0]) ? "an " : "a ") + word;
    // A lock held past the wait, wherever it comes (a run's end, `rig history`, --record): who and
    // how long, not SQLite's bare "database is locked" (a review).
    if (sqlite3_errcode(db_) == SQLITE_BUSY) {
      // The handler gave up (it waited), or SQLite refused without waiting (its deadlock case).
      const bool gave_up = lock_wait_.gave_up_after >= std::chrono::steady_clock::duration::zero();
      const auto waited = std::chrono::duration_cast<std::chrono::seconds>(lock_wait_.gave_up_after).count();
      lock_wait_.gave_up_after = std::chrono::steady_clock::duration(-1);
      throw LockedError(where_, std::string(kLockedByAnother) +
                                    (waited > 0 ? " for more than " + std::to_string(waited) + " s" : std::string()) +
                                    " (a write or a backup holding it): " + (gave_up ? "gave up waiting to " : "could not ") +
                                    (word == "SELECT" || word == "PRAGMA" ? "read it" : "write it") +
                                    "; try again once it is done");
    }
    throw ConfigError(where_ + ": cannot " + what + " " + kind + " statement: " + sqlite_said(db_));
  }
  static void bind(sqlite3_stmt* st, int i, const Value& v) {
    if (const auto* x = std::get_if<int64_t>(&v)) sqlite3_bind_int64(st, i, *x);
    else if (const auto* d = std::get_if<double>(&v)) sqlite3_bind_double(st, i, *d);
    else if (const auto* s = std::get_if<std::string>(&v))
      sqlite3_bind_text(st, i, s->c_str(), static_cast<int>(s->size()), SQLITE_TRANSIENT);
    else sqlite3_bind_null(st, i);
  }
  static Value column(sqlite3_stmt* st, int c) {
    switch (sqlite3_column_type(st, c)) {
      case SQLITE_INTEGER: return static_cast<int64_t>(sqlite3_column_int64(st, c));
      case SQLITE_FLOAT: return sqlite3_column_double(st, c);
      case SQLITE_NULL: return std::monostate{};
      default: {
        const auto* t = reinterpret_cast<const char*>(sqlite3_column_text(st, c));
        return std::string(t ? t : "", static_cast<std::size_t>(sqlite3_column_bytes(st, c)));
      }
    }
  }
  sqlite3* db_ = nullptr;
  LockWait lock_wait_;  // wait_for_lock's
};

// ---------------------------------------------------------------- PostgreSQL
// `?` placeholders -> $1..$n (outside quoted strings).
std::string pg_placeholders(const std::string& sql) {
  std::string out;
  int n = 0;
  bool quoted = false;
  for (char c : sql) {
    if (c == '\'') quoted = !quoted;
    if (c == '?' && !quoted) out += "$" + std::to_string(++n);
    else out += c;
  }
  return out;
}

// libpq is loaded when a PostgreSQL history is first opened, not linked: its dependency tree
// (Kerberos, LDAP, GnuTLS, OpenSSL: 22 shared libraries) made every rig command's start-up map
// and relocate them, 4-5 ms of CPU (about a tenth of `rig analyze` on an hour's record).
struct Pq {
  decltype(&PQconnectdb) connectdb;
  decltype(&PQstatus) status;
  decltype(&PQerrorMessage) errorMessage;
  decltype(&PQfinish) finish;
  decltype(&PQexecParams) execParams;
  decltype(&PQclear) clear;
  decltype(&PQresultStatus) resultStatus;
  decltype(&PQntuples) ntuples;
  decltype(&PQnfields) nfields;
  decltype(&PQgetisnull) getisnull;
  decltype(&PQgetvalue) getvalue;
  decltype(&PQftype) ftype;
};

const Pq& pq(const std::string& where) {
  static const std::optional<Pq> api = []() -> std::optional<Pq> {
    LazyLibrary lib("libpq.so.5");
    Pq p{};
    lib.get(p.connectdb, "PQconnectdb");
    lib.get(p.status, "PQstatus");
    lib.get(p.errorMessage, "PQerrorMessage");
    lib.get(p.finish, "PQfinish");
    lib.get(p.execParams, "PQexecParams");
    lib.get(p.clear, "PQclear");
    lib.get(p.resultStatus, "PQresultStatus");
    lib.get(p.ntuples, "PQntuples");
    lib.get(p.nfields, "PQnfields");
    lib.get(p.getisnull, "PQgetisnull");
    lib.get(p.getvalue, "PQgetvalue");
    lib.get(p.ftype, "PQftype");
    if (!lib.ok()) return std::nullopt;
    return p;
  }();
  if (!api)
    throw ConfigError(where + ": cannot load libpq.so.5 for the PostgreSQL history database "
                              "(Debian package libpq5)");
  return *api;
}

class PgDb final : public Db {
 public:
  explicit PgDb(const std::string& url) {
    where_ = mask_password(url);
    pq_ = &pq(where_);
    // A server that accepts and never answers held a run's ending for ever (a code review): the
    // connection is given 10 s unless the URL sets its own connect_timeout.
    std::string conninfo = url;
    if (conninfo.find("connect_timeout=") == std::string::npos)
      conninfo += (conninfo.find('?') == std::string::npos ? "?" : "&") + std::string("connect_timeout=10");
    conn_ = pq_->connectdb(conninfo.c_str());
    if (!conn_ || pq_->status(conn_) != CONNECTION_OK) {
      std::string msg = conn_ ? pq_->errorMessage(conn_) : "out of memory";
      while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' ')) msg.pop_back();
      pq_->finish(conn_);
      conn_ = nullptr;
      throw ConfigError(where_ + ": cannot connect to the history database: " + msg);
    }
    exec("SET client_min_messages = warning");  // no NOTICEs on stderr from IF NOT EXISTS
  }
  ~PgDb() override { pq_->finish(conn_); }

  std::vector<Row> query(const std::string& sql, const std::vector<Value>& params) override {
    std::vector<std::string> text(params.size());
    std::vector<const char*> ptrs(params.size(), nullptr);
    for (std::size_t i = 0; i < params.size(); ++i) {
      if (std::holds_alternative<std::monostate>(params[i])) continue;
      text[i] = as_text(params[i]);
      ptrs[i] = text[i].c_str();
    }
    const std::string q = pg_placeholders(sql);
    std::unique_ptr<PGresult, void (*)(PGresult*)> res(
        pq_->execParams(conn_, q.c_str(), static_cast<int>(params.size()), nullptr, ptrs.data(), nullptr, nullptr, 0),
        pq_->clear);
    const ExecStatusType st = res ? pq_->resultStatus(res.get()) : PGRES_FATAL_ERROR;
    if (st != PGRES_COMMAND_OK && st != PGRES_TUPLES_OK) {
      std::string msg = pq_->errorMessage(conn_);
      while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' ')) msg.pop_back();
      throw ConfigError(where_ + ": cannot run '" + sql.substr(0, 60) + "': " + msg);
    }
    std::vector<Row> rows;
    const int nr = pq_->ntuples(res.get()), nc = pq_->nfields(res.get());
    for (int r = 0; r < nr; ++r) {
      Row row;
      for (int c = 0; c < nc; ++c) row.push_back(cell(res.get(), r, c));
      rows.push_back(std::move(row));
    }
    return rows;
  }

  void begin_exclusive() override {
    exec("BEGIN");
    exec("SELECT pg_advisory_xact_lock(7201907)");  // one writer migrates/records at a time
  }
  std::string backend() const override { return "postgresql"; }
  std::string dialect_type(const std::string& word) const override {
    return word == "id" ? "BIGSERIAL PRIMARY KEY" : word;
  }
  bool has_table(const std::string& name) override {
    return !query("SELECT 1 FROM information_schema.tables WHERE table_schema = current_schema() AND table_name = ?",
                  {name})
                .empty();
  }

 private:
  // Text-format results typed from the column's type OID (pg_type.h values).
  Value cell(const PGresult* r, int row, int col) const {
    if (pq_->getisnull(r, row, col)) return std::monostate{};
    std::string s = pq_->getvalue(r, row, col);
    switch (pq_->ftype(r, col)) {
      case 20: case 21: case 23: return as_int(Value(s)).value_or(0);          // int8, int2, int4
      case 700: case 701: case 1700: return as_double(Value(s)).value_or(0.0);  // float4, float8, numeric
      default: return s;
    }
  }
  const Pq* pq_ = nullptr;
  PGconn* conn_ = nullptr;
};

}  // namespace


void set_lock_wait_ms(int ms) { lock_wait_ms = ms; }
void set_lock_wait_stop(std::function<bool()> stopped) { lock_wait_stopped = std::move(stopped); }
void set_lock_wait_notice(std::function<void(const std::string&, int)> notice) { lock_wait_notice = std::move(notice); }

std::unique_ptr<Db> open_db(const std::string& url, Access access) {
  // PostgreSQL: the server's database exists or the connection fails; nothing is created by opening.
  if (const auto path = sqlite_path(url)) return std::make_unique<SqliteDb>(*path, access);
  return std::make_unique<PgDb>(url);
}

}  // namespace rig::history
