// What a run folder's files say about its ending (app/run_seal.hpp), on folders written here:
// which outcome is final, and whether `rig run --resume` takes up an unfinished ending.
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include "app/run_seal.hpp"
#include "tests/report/fixture.hpp"

using rig::test::TempDir;
using nlohmann::json;

namespace {
void write(const std::filesystem::path& p, const std::string& text) { std::ofstream(p) << text; }

// A passport of `outcome` whose reason is `why` (the shape read_passport reads).
void passport(const TempDir& d, const std::string& outcome, const std::string& why) {
  json p = rig::test::fixture_passport("QA-1", outcome);
  p["aborted_reason"] = why;
  write(d.path / "passport.json", p.dump());
}

// A seal.json stating `outcome` ("" : a checkpoint's seal) over `files`, as far as a_resume_finishes
// reads it.
void seal(const TempDir& d, const std::string& outcome, const std::vector<std::string>& files = {"passport.json"}) {
  json listed = json::object();
  for (const std::string& f : files) listed[f] = "0";
  write(d.path / "seal.json", json{{"schema", "rig.seal/1"}, {"outcome", outcome}, {"files", listed}}.dump());
}
}  // namespace

// A verdict is final; so is an ERROR or ABORTED ending whose run.log lost lines (no resume), and
// only that one: any other stopped run goes on with its resume.
TEST(RunFolder, AFinalOutcomeIsAVerdictOrAnEndingWithNoResume) {
  TempDir d;
  const std::string lost = "run.log is missing lines: the disk refused 3 line(s), the first at 2026-12-06T08:00:00.000Z (x)";
  for (const char* v : {"PASS", "FAIL"}) {
    passport(d, v, "");
    EXPECT_EQ(rig::cli::final_outcome_of(d.path.string()), v);
  }
  for (const char* o : {"ERROR", "ABORTED"}) {
    passport(d, o, "SIGINT received");
    EXPECT_EQ(rig::cli::final_outcome_of(d.path.string()), "");
    EXPECT_EQ(rig::cli::earlier_log_missing_lines(d.path.string()), "");
    passport(d, o, std::string("SIGINT received; ") + lost);
    EXPECT_EQ(rig::cli::final_outcome_of(d.path.string()), o);
    EXPECT_EQ(rig::cli::earlier_log_missing_lines(d.path.string()), std::string("SIGINT received; ") + lost);
  }
}

// The resume takes up every unfinished ending but one with no resume whose own files (`ending`)
// or whose final seal are what is missing: only computing the ending again gives those, and that
// resume is refused (a code review: `rig verify` advised it). A `seal` listed beside a final seal
// in place is a list not brought up to date: taken up.
TEST(RunFolder, AResumeFinishesAnEndingWithNoResumeOnlyUnderItsFinalSeal) {
  TempDir d;
  const std::string dir = d.path.string();
  using Steps = std::vector<std::string>;
  passport(d, "ERROR", "SIGINT received");  // a resume goes on with the run
  for (const Steps& s : {Steps{"report"}, Steps{"ending", "junit"}, Steps{"seal", "history"}})
    EXPECT_TRUE(rig::cli::a_resume_finishes(dir, s));
  passport(d, "ERROR", "run.log is missing lines: the disk refused 1 line(s), the first at t (x)");
  EXPECT_TRUE(rig::cli::a_resume_finishes(dir, {"report", "history"}));
  EXPECT_TRUE(rig::cli::a_resume_finishes(dir, {"junit"}));
  EXPECT_FALSE(rig::cli::a_resume_finishes(dir, {"ending", "junit"}));
  EXPECT_FALSE(rig::cli::a_resume_finishes(dir, {"seal", "history"}));  // no seal.json at all
  seal(d, "");  // the last checkpoint's
  EXPECT_FALSE(rig::cli::a_resume_finishes(dir, {"seal", "history"}));
  seal(d, "ERROR");  // the final seal written, the list not yet brought up to date
  EXPECT_TRUE(rig::cli::a_resume_finishes(dir, {"seal", "history"}));
  // An earlier attempt's final seal is not this ending's: another outcome, or no passport sealed.
  seal(d, "ABORTED");
  EXPECT_FALSE(rig::cli::a_resume_finishes(dir, {"seal", "history"}));
  seal(d, "ERROR", {"run.json", "checkpoint.json"});
  EXPECT_FALSE(rig::cli::a_resume_finishes(dir, {"seal", "history"}));
  write(d.path / "seal.json", "{not json");
  EXPECT_FALSE(rig::cli::a_resume_finishes(dir, {"seal"}));
}
