// A minimal SQL connection with two backends (SQLite, PostgreSQL/libpq) so the history
// code writes one set of SQL statements. Dialect shim: statements use `?` placeholders
// (rewritten to $1..$n for PostgreSQL) and the few type words that differ go through
// Db::dialect_type().
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "rig/core/errors.hpp"
#include "rig/report/db_url.hpp"

namespace rig::history {

// A bound parameter or a result cell.
using Value = std::variant<std::monostate, int64_t, double, std::string>;
using Row = std::vector<Value>;

std::optional<double> as_double(const Value& v);
std::optional<int64_t> as_int(const Value& v);
std::string as_text(const Value& v);  // "" for NULL

class Db {
 public:
  virtual ~Db() = default;
  Db() = default;
  Db(const Db&) = delete;
  Db& operator=(const Db&) = delete;

  // Runs a statement; returns its result rows (empty for statements without any).
  virtual std::vector<Row> query(const std::string& sql, const std::vector<Value>& params = {}) = 0;
  void exec(const std::string& sql, const std::vector<Value>& params = {}) { query(sql, params); }

  // A write transaction that also serialises schema migrations between processes
  // (SQLite: BEGIN IMMEDIATE; PostgreSQL: BEGIN + a transaction-scoped advisory lock).
  virtual void begin_exclusive() = 0;
  void commit() { exec("COMMIT"); }
  void rollback() noexcept;

  // "sqlite" or "postgresql".
  virtual std::string backend() const = 0;
  // Type words that differ: "id" -> the auto-increment primary key column type.
  virtual std::string dialect_type(const std::string& word) const = 0;
  // Whether a table exists.
  virtual bool has_table(const std::string& name) = 0;
  // The URL with any password masked, for messages.
  const std::string& where() const { return where_; }

 protected:
  std::string where_;
};

// How a database is opened. Reading commands use ReadOnly: they never create a database
// (a mistyped path must not leave an empty one behind) nor change one.
enum class Access { ReadWrite, ReadOnly };

// Opens `url` ("sqlite:PATH", a plain path, "postgresql://...", "postgres://...").
// ReadWrite: SQLite files and their folder are created when missing. ReadOnly: a missing
// SQLite file is an error; one this account may write is opened read-write with its statements
// held to reading (PRAGMA query_only), so that a journal an interrupted writer left is rolled
// back; otherwise read-only (SQLITE_OPEN_READONLY), and such a journal is a ConfigError saying so.
// Throws rig::ConfigError.
std::unique_ptr<Db> open_db(const std::string& url, Access access = Access::ReadWrite);

// How long a SQLite connection waits for another writer's lock (read on every retry): 10 s, enough
// for several rig processes writing one file. A run being stopped shortens it (`rig run` on a
// signal: a stop's grace is often 10 s, docker's, and a locked database held the exit that long,
// a line integrator's review); the row then waits in .ending-pending for the resume.
void set_lock_wait_ms(int ms);
// Asked on every retry of a wait for another writer's lock, one already under way included: once
// it says stopped, the wait ends 2 s after it began (or at set_lock_wait_ms's limit, if shorter).
// A signal that came while the ending waited held the exit the whole 10 s (a review). Set once,
// before any connection waits (`rig run`: its cancel token).
void set_lock_wait_stop(std::function<bool()> stopped);
inline constexpr int kStoppedLockWaitMs = 2000;
// Told once a wait for another writer's lock has lasted kLockWaitNoticeMs, with the database
// ("sqlite:PATH") and the wait's limit: a `rig history` waited 10 s saying nothing (a review).
// Set once, before any connection waits (main: a line on stderr).
void set_lock_wait_notice(std::function<void(const std::string& where, int limit_ms)> notice);
inline constexpr int kLockWaitNoticeMs = 1000;
// The words a lock held past the wait is reported with (Db's errors begin "<where>: " then these).
inline constexpr const char* kLockedByAnother = "locked by another process";
// A lock held past the wait: what() is "<where>: <reason>", `reason` beginning with
// kLockedByAnother, so a caller names the database its own way and keeps the words (a path that
// holds those words is not taken for a lock: a code review).
struct LockedError : ConfigError {
  LockedError(const std::string& where, std::string why) : ConfigError(where + ": " + why), reason(std::move(why)) {}
  std::string reason;
};


// Keeps a transaction open until commit(); rolls back if destroyed before.
class Transaction {
 public:
  explicit Transaction(Db& db) : db_(db) { db_.begin_exclusive(); }
  ~Transaction() {
    if (!done_) db_.rollback();
  }
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  void commit() {
    db_.commit();
    done_ = true;
  }

 private:
  Db& db_;
  bool done_ = false;
};

}  // namespace rig::history
