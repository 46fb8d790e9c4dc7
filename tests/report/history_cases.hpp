// History checks shared by the SQLite and PostgreSQL suites: the same calls and the same
// expectations against either backend (the SQL is the same; only the connection differs).
#pragma once
#include <gtest/gtest.h>

#include "rig/core/errors.hpp"
#include "rig/report/history.hpp"
#include "tests/report/fixture.hpp"

namespace rig::test {

// Three DUTs, five runs, one aborted; returns nothing, checks everything.
inline void history_round_trip(const std::string& url, const std::string& run_root) {
  namespace h = rig::history;
  EXPECT_EQ(h::migrate(url), 0);  // new database
  EXPECT_EQ(h::migrate(url), h::current_schema_version());

  struct R { const char* serial; const char* outcome; const char* started; double b; };
  const R runs[] = {{"SN-1", "PASS", "2026-11-01T08:00:00Z", 2.1e-6},
                    {"SN-2", "FAIL", "2026-11-02T08:00:00+03:00", 6.5e-6},
                    {"SN-1", "PASS", "2026-11-03T09:30:00Z", 2.4e-6},
                    {"SN-3", "ABORTED", "2026-11-04T10:00:00Z", 0},
                    {"SN-1", "PASS", "2026-11-05T07:00:00Z", 2.9e-6}};
  std::vector<long long> ids;
  int i = 0;
  for (const R& r : runs) {
    json p = fixture_passport(r.serial, r.outcome, r.started);
    p["values"]["in_run_b_allan"]["value"] = r.b;
    if (std::string(r.outcome) == "ABORTED") {
      p["values"].erase("in_run_b_allan");
      p["aborted_reason"] = "e-stop line";
      p["captures"] = json::array({"captures/run01-U10.cap"});
    }
    ids.push_back(h::record_run(url, p, run_root + "/run" + std::to_string(++i)).id);
  }
  // Recording the same run again replaces it (same folder + start), keeps one row and its id (a
  // reference to the run stays valid; it used to get a new id each time, a review).
  json again = fixture_passport("SN-1", "PASS", "2026-11-05T07:00:00Z");
  again["values"]["in_run_b_allan"]["value"] = 3.0e-6;
  again["captures"] = json::array({"captures/run01-U10.cap"});
  const long long replaced = h::record_run(url, again, run_root + "/run5").id;
  EXPECT_EQ(replaced, ids.back());

  const auto all = h::list_runs(url, {});
  ASSERT_EQ(all.size(), 5u);
  EXPECT_EQ(all[0].serial, "SN-1");
  EXPECT_EQ(all[1].started, "2026-11-02T05:00:00Z");  // +03:00 normalised to UTC
  EXPECT_EQ(all[1].outcome, "FAIL");
  EXPECT_EQ(all[3].outcome, "ABORTED");
  EXPECT_EQ(all[3].aborted_reason, "e-stop line");
  EXPECT_EQ(all[3].captures, std::vector<std::string>{"captures/run01-U10.cap"});
  EXPECT_EQ(all[0].captures.size(), 3u);
  EXPECT_EQ(all[0].profile, "paper");
  EXPECT_EQ(all[0].plant, "emulated");
  EXPECT_EQ(all[0].software, "rig 0.1.0");
  EXPECT_EQ(all[0].finished, "2026-11-20T09:52:31Z");
  EXPECT_TRUE(all[0].run_dir.size() > 5 && all[0].run_dir.substr(all[0].run_dir.size() - 5) == "/run1");
  EXPECT_FALSE(all[0].station.empty());
  EXPECT_EQ(all[4].id, ids.back());
  EXPECT_EQ(all[4].captures, std::vector<std::string>{"captures/run01-U10.cap"});  // the new record's, not both

  h::Filter f;
  f.serial = "SN-1";
  const auto sn1 = h::list_runs(url, f);
  ASSERT_EQ(sn1.size(), 3u);
  f.since = "2026-11-03";
  EXPECT_EQ(h::list_runs(url, f).size(), 2u);
  f.until = "2026-11-05";
  EXPECT_EQ(h::list_runs(url, f).size(), 1u);
  h::Filter lim;
  lim.limit = 2;
  const auto newest = h::list_runs(url, lim);
  ASSERT_EQ(newest.size(), 2u);
  EXPECT_EQ(newest[0].serial, "SN-3");  // the two newest, oldest first
  EXPECT_EQ(newest[1].started, "2026-11-05T07:00:00Z");
  EXPECT_EQ(newest[1].captures, all[4].captures) << "the child rows of the listed runs (read for them alone)";
  h::Filter bad;
  bad.since = "last tuesday";
  EXPECT_THROW(h::list_runs(url, bad), ConfigError);

  // The trend of one value across DUTs, and across the runs of one DUT.
  const auto tr = h::trend(url, "in_run_b_allan", {});
  ASSERT_EQ(tr.size(), 4u);  // the aborted run has no such value
  EXPECT_DOUBLE_EQ(*tr[0].value, 2.1e-6);
  EXPECT_DOUBLE_EQ(*tr[1].value, 6.5e-6);
  EXPECT_DOUBLE_EQ(*tr[3].value, 3.0e-6);  // the replaced record
  EXPECT_EQ(tr[0].unit, "g");
  EXPECT_DOUBLE_EQ(*tr[0].lo, 1.8e-6);
  EXPECT_FALSE(tr[0].limit_min.has_value());
  EXPECT_DOUBLE_EQ(*tr[0].limit_max, 5e-6);
  h::Filter one;
  one.serial = "SN-1";
  const auto tr1 = h::trend(url, "in_run_b_allan", one);
  EXPECT_EQ(tr1.size(), 3u);
  const auto r = h::trend(url, "r", {});
  ASSERT_FALSE(r.empty());
  EXPECT_FALSE(r[0].value.has_value());  // null value with its reason
  EXPECT_EQ(r[0].reason, "needs a record longer than 50 h");
  const auto names = h::value_names(url);
  EXPECT_NE(std::find(names.begin(), names.end(), "bias"), names.end());

  // A passport without the fields the schema needs is refused.
  EXPECT_THROW(h::record_run(url, json{{"outcome", "PASS"}}, run_root), ConfigError);
  EXPECT_THROW(h::record_run(url, json::array(), run_root), ConfigError);
}

// Every ending of a run is kept (a review: a folder put back to its state before a FAIL and
// resumed replaced the FAIL's row, and the FAIL was gone from the history).
inline void history_keeps_every_ending(const std::string& url, const std::string& run_root) {
  namespace h = rig::history;
  const std::string dir = run_root + "/rolled-back";
  auto ending = [&](const char* outcome, const char* finished) {
    json p = fixture_passport("SN-9", outcome, "2026-11-07T08:00:00Z");
    p["finished"] = finished;
    if (std::string(outcome) == "ABORTED") p["aborted_reason"] = "SIGINT";
    return h::record_run(url, p, dir);
  };
  const h::Recorded fail = ending("FAIL", "2026-11-07T10:00:00Z");
  EXPECT_EQ(fail.endings, 1);
  EXPECT_FALSE(fail.replaced_verdict);
  EXPECT_EQ(ending("FAIL", "2026-11-07T10:00:00Z").endings, 1);  // the same ending recorded again
  const h::Recorded aborted = ending("ABORTED", "2026-11-07T10:05:00Z");
  EXPECT_EQ(aborted.id, fail.id);  // one run, one id
  EXPECT_EQ(aborted.endings, 2);
  ASSERT_TRUE(aborted.replaced_verdict);
  EXPECT_EQ(*aborted.replaced_verdict, "FAIL");
  EXPECT_EQ(aborted.replaced_finished, "2026-11-07T10:00:00Z");
  EXPECT_NE(h::replaced_verdict_note(aborted, "ABORTED").find("rig history --endings " + std::to_string(fail.id)),
            std::string::npos);
  // Another ABORTED ending in the same second (a resume stopped at once): its own ending, not the
  // last one again (a review: same outcome and finish time were taken for the same ending).
  json again = fixture_passport("SN-9", "ABORTED", "2026-11-07T08:00:00Z");
  again["finished"] = "2026-11-07T10:05:00Z";
  again["aborted_reason"] = "SIGINT";
  again["values"]["bias"]["value"] = nullptr;
  EXPECT_EQ(h::record_run(url, again, dir).endings, 3);
  // A PASS after them: the FAIL recorded before is still the verdict this ending replaces, said
  // with the ABORTED endings between (a review: only the ending just before was compared).
  const h::Recorded pass = ending("PASS", "2026-11-07T10:30:00Z");
  ASSERT_TRUE(pass.replaced_verdict);
  EXPECT_EQ(*pass.replaced_verdict, "FAIL");
  EXPECT_EQ(pass.endings, 4);
  EXPECT_FALSE(ending("PASS", "2026-11-07T10:30:00Z").replaced_verdict);  // the same ending again: nothing new

  h::Filter f;
  f.serial = "SN-9";
  const auto runs = h::list_runs(url, f);
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].outcome, "PASS");
  EXPECT_EQ(runs[0].earlier, (std::vector<std::string>{"FAIL", "ABORTED", "ABORTED"}));
  const auto e = h::endings_of(url, fail.id);
  ASSERT_EQ(e.size(), 4u);
  EXPECT_EQ(e[0].outcome, "FAIL");
  EXPECT_EQ(e[0].finished, "2026-11-07T10:00:00Z");
  EXPECT_EQ(e[1].outcome, "ABORTED");
  EXPECT_EQ(e[1].aborted_reason, "SIGINT");
  EXPECT_EQ(e[3].seq, 3);
  EXPECT_EQ(e[3].outcome, "PASS");
  EXPECT_FALSE(e[3].recorded.empty());
  EXPECT_TRUE(h::endings_of(url, 999999).empty());
}

// A run is its folder, start time, DUT and station: two stations sharing a database that write a
// folder of the same path in the same second, or a line that starts the next DUT in a folder of
// the same path within the second, are two runs (a review: one row, DUT-A's record gone).
inline void history_tells_runs_of_one_folder_and_second_apart(const std::string& url, const std::string& run_root) {
  namespace h = rig::history;
  const std::string dir = run_root + "/current";
  auto record = [&](const char* serial, const char* station) {
    json p = fixture_passport(serial, "PASS", "2026-11-08T08:00:00Z");
    p["station"] = station;
    return h::record_run(url, p, dir);
  };
  const h::Recorded a = record("DUT-A", "line-1 station 1");
  const h::Recorded b = record("DUT-B", "line-1 station 2");
  const h::Recorded c = record("DUT-C", "line-1 station 1");
  const h::Recorded a2 = record("DUT-A", "line-1 station 2");
  EXPECT_NE(a.id, b.id);
  EXPECT_NE(a.id, c.id);
  EXPECT_NE(a.id, a2.id);
  EXPECT_EQ(record("DUT-A", "line-1 station 1").id, a.id);  // the same run recorded again
  // A run stopped before its DUT gave a serial, then resumed: one run (a re-test: two rows).
  json early = fixture_passport("", "ABORTED", "2026-11-08T09:00:00Z");
  early["station"] = "line-1 station 1";
  const h::Recorded stopped = h::record_run(url, early, dir);
  json resumed = fixture_passport("DUT-D", "PASS", "2026-11-08T09:00:00Z");
  resumed["station"] = "line-1 station 1";
  const h::Recorded finished = h::record_run(url, resumed, dir);
  EXPECT_EQ(finished.id, stopped.id);
  EXPECT_EQ(finished.endings, 2);
  for (const char* serial : {"DUT-A", "DUT-B", "DUT-C"}) {
    h::Filter f;
    f.serial = serial;
    EXPECT_EQ(h::list_runs(url, f).size(), std::string(serial) == "DUT-A" ? 2u : 1u) << serial;
  }
}

}  // namespace rig::test
