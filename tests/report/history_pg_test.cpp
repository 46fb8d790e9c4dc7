// The results database on a real PostgreSQL server started by the test (label `postgres`).
#include <gtest/gtest.h>

#include <thread>

#include "rig/report/history.hpp"
#include "tests/report/history_cases.hpp"
#include "tests/report/pg_server.hpp"

namespace {

using nlohmann::json;
using rig::test::PgServer;
using rig::test::TempDir;
namespace h = rig::history;

// One server for the suite (initdb costs about a second).
class HistoryPg : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { server_ = new PgServer(); }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
  }
  void SetUp() override {
    if (!server_->available()) GTEST_SKIP() << "PostgreSQL server binaries not installed (Debian package postgresql)";
  }
  // A fresh database per test.
  std::string fresh_db(const std::string& name) {
    server_->psql("postgres", "CREATE DATABASE " + name);
    return server_->url(name);
  }
  static PgServer* server_;
};
PgServer* HistoryPg::server_ = nullptr;

TEST_F(HistoryPg, RoundTripFiltersAndTrend) {
  TempDir d;
  rig::test::history_round_trip(fresh_db("roundtrip"), d.path.string());
}

TEST_F(HistoryPg, EveryEndingOfARunIsKept) {
  TempDir d;
  rig::test::history_keeps_every_ending(fresh_db("endings"), d.path.string());
}

TEST_F(HistoryPg, RunsOfOneFolderAndSecondOnTwoStationsOrDutsAreTwoRuns) {
  TempDir d;
  rig::test::history_tells_runs_of_one_folder_and_second_apart(fresh_db("identity"), d.path.string());
}

// Version 1 as released, in PostgreSQL's dialect (frozen copy of its DDL).
constexpr const char* kSchemaV1 =
    "CREATE TABLE schema_version (version INTEGER NOT NULL PRIMARY KEY, applied TEXT NOT NULL);"
    "INSERT INTO schema_version VALUES (1, '2026-10-01T00:00:00Z');"
    "CREATE TABLE runs (id BIGSERIAL PRIMARY KEY, serial TEXT NOT NULL, profile TEXT, plant TEXT, software TEXT, "
    "started TEXT, finished TEXT, outcome TEXT NOT NULL, run_dir TEXT NOT NULL, passport TEXT NOT NULL);"
    "CREATE UNIQUE INDEX runs_dir_started ON runs (run_dir, started);"
    "CREATE INDEX runs_serial_started ON runs (serial, started);"
    "CREATE TABLE run_values (run_id BIGINT NOT NULL REFERENCES runs (id) ON DELETE CASCADE, name TEXT NOT NULL, "
    "value DOUBLE PRECISION, unit TEXT, lo DOUBLE PRECISION, hi DOUBLE PRECISION, limit_min DOUBLE PRECISION, "
    "limit_max DOUBLE PRECISION, outcome TEXT, reason TEXT, PRIMARY KEY (run_id, name));";

TEST_F(HistoryPg, MigratesAVersion1Database) {
  const std::string url = fresh_db("old");
  server_->psql("old", kSchemaV1);
  json p = rig::test::fixture_passport("OLD-1", "ABORTED", "2026-10-02T10:00:00Z");
  p["aborted_reason"] = "e-stop";
  server_->psql("old", "INSERT INTO runs (serial, outcome, run_dir, started, passport) VALUES ('OLD-1', 'ABORTED', "
                       "'/runs/old1', '2026-10-02T10:00:00Z', $json$" + p.dump() + "$json$)");
  EXPECT_EQ(h::migrate(url), 1);
  const auto runs = h::list_runs(url, {});
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].aborted_reason, "e-stop");
  EXPECT_EQ(runs[0].captures.size(), 3u);
  const auto ends = h::endings_of(url, runs[0].id);  // v3's data step: the run's one ending
  ASSERT_EQ(ends.size(), 1u);
  EXPECT_EQ(ends[0].aborted_reason, "e-stop");
  EXPECT_EQ(h::migrate(url), h::current_schema_version());
}

TEST_F(HistoryPg, SeveralRigsRecordIntoOneDatabaseAtOnce) {
  const std::string url = fresh_db("line");
  TempDir d;
  std::vector<std::thread> rigs;
  for (int r = 0; r < 4; ++r)  // every rig also races to create the schema
    rigs.emplace_back([&, r] {
      for (int i = 0; i < 5; ++i) {
        char started[32];
        std::snprintf(started, sizeof started, "2026-11-%02dT%02d:00:00Z", r + 1, i);
        h::record_run(url, rig::test::fixture_passport("R" + std::to_string(r), "PASS", started),
                      (d.path / ("rig" + std::to_string(r))).string());
      }
    });
  for (auto& t : rigs) t.join();
  EXPECT_EQ(h::list_runs(url, {}).size(), 20u);
  EXPECT_EQ(h::trend(url, "bias", {}).size(), 20u);
}

TEST(HistoryPgClient, UnreachableServerIsAConfigErrorWithoutThePassword) {
  try {
    h::migrate("postgresql://rig:s3cret@/postgres?host=/nonexistent-dir&port=1&connect_timeout=2");
    FAIL() << "no exception";
  } catch (const rig::ConfigError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("postgresql://rig:***@"), std::string::npos) << w;
    EXPECT_EQ(w.find("s3cret"), std::string::npos) << w;
    EXPECT_NE(w.find("cannot connect"), std::string::npos) << w;
  }
}

}  // namespace
