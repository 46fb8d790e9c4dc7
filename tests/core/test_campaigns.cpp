// Issue 13's campaigns as tests: a run aborted or killed at random points, with the random
// points drawn from fixed seeds in device time (`--inject KIND@T` fires at device time T, so
// each point is reproducible to the sample whatever the machine's load), then resumed.
// Asserted every time: the exit code (3 aborted, 128+9 killed), the safe state in order in
// run.log, the outcome, and that the resumed passport equals the uninterrupted run's with the
// same seed bit for bit (minus kSessionFields). The damaged-checkpoint cases extend
// RigCli.DamagedCheckpointsAreRefusedNamingFileAndField (test_rig_cli.cpp).
#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "rig/capture/capture.hpp"
#include "rig/seal/seal.hpp"
#include "tests/core/rig_process.hpp"

namespace fs = std::filesystem;
using namespace rig::test;
using nlohmann::json;

namespace {

// What legitimately differs between a resumed run and an uninterrupted one: when and where it
// ran (started, finished, out_dir) and, per phase, what this session did with it (status
// "skipped" for a phase completed before the resume, its times and message). Everything else
// of passport.json (serial, profile, plant, station, software, outcome, every value with its
// limits, reason and outcome, captures, phase ids and titles) must be equal.
const char* kSessionFields[] = {"started", "finished", "out_dir"};
const char* kSessionPhaseFields[] = {"status", "started", "finished", "message"};

json without_session_fields(json p) {
  for (const char* f : kSessionFields) p.erase(f);
  for (auto& ph : p["phases"])
    for (const char* f : kSessionPhaseFields) ph.erase(f);
  return p;
}

json read_json(const std::string& path) { return json::parse(slurp(path)); }

// The ci profile's run takes 228.5 s of device time (bring-up 7.7 s, the loop phase from
// 227.5 s); the random points are drawn from [0, kCiDeviceS), where every one interrupts it.
constexpr double kCiDeviceS = 228.0;
constexpr double kCiLoopPhaseS = 227.9;  // a fixed point inside the short loop phase
constexpr double kPaperDeviceS = 6800.0;  // 114 min

// The uninterrupted run the campaigns compare with.
struct Reference {
  json passport, analysis;
};
Reference uninterrupted(const std::string& d, const std::string& profile, std::vector<std::string> extra = {}) {
  std::vector<std::string> args = {"run", "--profile", profile, "--yes", "--no-history", "--out", d + "/whole"};
  args.insert(args.end(), extra.begin(), extra.end());
  EXPECT_EQ(run(args, d + "/whole-io"), 0) << slurp(d + "/whole-io.stderr");
  return {read_json(d + "/whole/passport.json"), read_json(d + "/whole/analysis.json")};
}

// run.log holds the three safe-state steps in order, then "safe state reached".
void expect_safe_state_in_order(const std::string& log, const std::string& what) {
  const auto t = log.find("safe state 1/3: stopping table");
  const auto s = log.find("safe state 2/3: stopping DUT stream");
  const auto p = log.find("safe state 3/3: DUT power off");
  const auto r = log.find("safe state reached");
  ASSERT_NE(t, std::string::npos) << what << "\n" << log;
  EXPECT_LT(t, s) << what;
  EXPECT_LT(s, p) << what;
  EXPECT_LT(p, r) << what;
}

// Resumes `run_dir` (no fault injected) and checks the result against the uninterrupted run.
void resume_and_compare(const std::string& run_dir, const Reference& ref, const std::string& what) {
  const int rc = run({"run", "--resume", run_dir, "--yes", "--no-history"}, run_dir + "-resume");
  ASSERT_EQ(rc, 0) << what << "\n" << slurp(run_dir + "-resume.stderr");
  const json p = read_json(run_dir + "/passport.json");
  EXPECT_EQ(without_session_fields(p), without_session_fields(ref.passport))
      << what << ": the resumed passport differs from the uninterrupted run's";
  EXPECT_EQ(read_json(run_dir + "/analysis.json"), ref.analysis) << what << ": analysis.json differs";
  EXPECT_FALSE(fs::exists(run_dir + "/.fast-forward")) << what << ": the replay's scratch folder is left behind";
  const std::string log = slurp(run_dir + "/run.log");
  EXPECT_EQ(log.find("does not reproduce"), std::string::npos) << what << "\n" << log;
}

std::vector<double> random_points(unsigned seed, int n, double lo, double hi) {
  std::mt19937_64 g(seed);  // fixed: the campaign is the same on every machine and every run
  std::vector<double> t;
  for (int i = 0; i < n; ++i) {
    const double u = static_cast<double>(g() >> 11) * 0x1.0p-53;
    t.push_back(lo + (hi - lo) * u);
  }
  std::sort(t.begin(), t.end());
  return t;
}

// Rewrites a capture in place through the rig's own writer, `edit` applied to its header and
// samples: a capture as another build, or another DUT, would have written it.
void rewrite_capture(const std::string& path,
                     const std::function<void(rig::capture::Header&, std::vector<rig::Sample>&)>& edit) {
  rig::capture::Loaded l = rig::capture::load(path);
  edit(l.header, l.samples);
  fs::remove(path);
  rig::capture::Writer w(path, l.header);
  w.append(l.samples);
  w.close();
}

// The mean of channel x as the recorder sums it (float into double, in order).
double mean_x(const std::vector<rig::Sample>& s) {
  double sum = 0;
  for (const rig::Sample& v : s) sum += v.x_g;
  return sum / static_cast<double>(s.size());
}

std::string fmt_t(double t) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f", t);
  return b;
}

}  // namespace

// Issue 13, 7: SIGKILL at random device times (inside captures, at phase boundaries, during
// analysis), then --resume: exit 137, no passport, and the resumed passport equals the
// uninterrupted run's. Fails on the code before the fast-forward (the resumed plant restarted
// its noise from device time 0: 26 of 27 paper resumes differed).
TEST(Campaign, SigkillAtRandomPointsThenResumeEqualsTheUninterruptedRun) {
  const std::string d = tmp("campaign-kill");
  fs::create_directories(d);
  const Reference ref = uninterrupted(d, "ci");
  int k = 0;
  std::vector<double> points = random_points(1301, 6, 8.0, kCiDeviceS);
  points.push_back(kCiLoopPhaseS);
  for (const double t : points) {
    const std::string r = d + "/k" + std::to_string(++k), what = "sigkill@" + fmt_t(t);
    EXPECT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", r, "--inject", what}, r + "-io"),
              128 + SIGKILL)
        << what << "\n" << slurp(r + "-io.stderr");
    EXPECT_FALSE(fs::exists(r + "/passport.json")) << what;
    resume_and_compare(r, ref, what);
  }
}

// Issue 13, 7: a run killed before its first checkpoint (during bring-up, inside the first
// capture) resumes in the same folder from bring-up, with the uninterrupted run's result.
TEST(Campaign, RunKilledBeforeTheFirstCheckpointResumesFromBringUp) {
  const std::string d = tmp("campaign-early");
  fs::create_directories(d);
  const Reference ref = uninterrupted(d, "ci");
  for (const double t : {0.5, 3.0, 8.5}) {  // power-up, homing, the first run's capture
    const std::string r = d + "/at" + fmt_t(t), what = "sigkill@" + fmt_t(t);
    EXPECT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", r, "--inject", what}, r + "-io"),
              128 + SIGKILL);
    ASSERT_FALSE(fs::exists(r + "/checkpoint.json")) << what << ": a phase completed before the kill";
    // The dry run says so (it said "checkpoint.json checked with the records it names").
    EXPECT_EQ(run({"run", "--resume", r, "--dry-run"}, r + "-dry"), 0) << slurp(r + "-dry.stderr");
    EXPECT_NE(slurp(r + "-dry.stdout").find("Resume: " + r + " has no checkpoint (the run stopped before its first "
                                            "phase completed); 0 of "),
              std::string::npos)
        << slurp(r + "-dry.stdout");
    resume_and_compare(r, ref, what);
    EXPECT_NE(slurp(r + "/run.log").find("no checkpoint (stopped before the first phase completed)"),
              std::string::npos)
        << what;
    EXPECT_EQ(slurp(r + "/run.log").find("replayed the kept recordings"), std::string::npos)
        << what << ": nothing was replayed (bring-up's device time is not a replay)";
  }
  // The folder's profile.toml edited before the first checkpoint (limits loosened): run.json's
  // digest refuses the resume, as the checkpoint's would (it resumed to PASS: an automation review).
  const std::string e = d + "/edited";
  // SIGKILL, not SIGINT: a SIGINT is taken by the signal thread a moment later, when the emulated
  // plant (2000x real time) may have finished the first phase (a loaded CI machine did).
  ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", e, "--inject", "sigkill@0.5"}, e + "-io"),
            128 + SIGKILL);
  ASSERT_FALSE(fs::exists(e + "/checkpoint.json"));
  EXPECT_TRUE(read_json(e + "/run.json").contains("profile_digest"));
  std::ofstream(e + "/profile.toml", std::ios::app) << "\n# a comment changes nothing\n";
  EXPECT_EQ(run({"run", "--resume", e, "--dry-run"}, e + "-dry0"), 0) << slurp(e + "-dry0.stderr");
  std::string text = slurp(e + "/profile.toml");
  const std::string tight = "bias = [-1.0e-3, 1.0e-3]";
  ASSERT_NE(text.find(tight), std::string::npos) << text;
  text.replace(text.find(tight), tight.size(), "bias = [-1.0, 1.0]");
  std::ofstream(e + "/profile.toml") << text;
  for (const char* how : {"--dry-run", "--yes"}) {
    EXPECT_EQ(run({"run", "--resume", e, how}, e + "-r"), 2) << how << ": " << slurp(e + "-r.stderr");
    EXPECT_NE(slurp(e + "-r.stderr").find(e + "/run.json: field 'profile_digest': "), std::string::npos)
        << slurp(e + "-r.stderr");
    EXPECT_NE(slurp(e + "-r.stderr").find("not the profile the run started with (edited since?)"), std::string::npos);
    EXPECT_EQ(slurp(e + "-r.stderr").find("digests to"), std::string::npos) << "the profile's own digest is not handed over";
  }
  EXPECT_FALSE(fs::exists(e + "/passport.json")) << "nothing written by the refused resumes";
  // Without the digest in run.json (deleted; a rig before it wrote one) and no checkpoint, nothing
  // ties the folder's profile to the run's: refused (a re-test: an edited profile ran to PASS).
  nlohmann::json inv = read_json(e + "/run.json");
  inv.erase("profile_digest");
  std::ofstream(e + "/run.json") << inv.dump(2);
  EXPECT_EQ(run({"run", "--resume", e, "--yes"}, e + "-nodigest"), 2) << slurp(e + "-nodigest.stderr");
  EXPECT_NE(slurp(e + "-nodigest.stderr").find(e + "/run.json: no field 'profile_digest', and no checkpoint"),
            std::string::npos)
      << slurp(e + "-nodigest.stderr");
  EXPECT_FALSE(fs::exists(e + "/passport.json"));
}

// The loop test's records of an attempt the checkpoint does not hold (the run stopped after
// the loop test wrote them, before its checkpoint: a full disk in a review) are kept as
// loop-test.csv.interrupted-1 when the resume tests the loop again, never overwritten; the
// resumed passport is the uninterrupted run's, and a sealed folder still verifies.
TEST(Campaign, AResumeKeepsAnEarlierAttemptsLoopTestRecords) {
  const std::string d = tmp("campaign-loop-kept");
  fs::create_directories(d);
  const Reference ref = uninterrupted(d, "ci");
  const std::string r = d + "/killed";
  ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", r, "--inject", "sigkill@150"}, r + "-io"),
            128 + SIGKILL);
  ASSERT_FALSE(fs::exists(r + "/loop-test.csv")) << "killed after the loop test: choose an earlier point";
  std::ofstream(r + "/loop-test.csv") << "# an earlier attempt's records\n";
  resume_and_compare(r, ref, "loop-test.csv of an earlier attempt");
  EXPECT_EQ(slurp(r + "/loop-test.csv.interrupted-1"), "# an earlier attempt's records\n");
  EXPECT_EQ(slurp(r + "/loop-test.csv"), slurp(d + "/whole/loop-test.csv"));
  EXPECT_NE(slurp(r + "/run.log").find("an earlier attempt's loop-test records are kept as loop-test.csv.interrupted-1"),
            std::string::npos)
      << slurp(r + "/run.log");
}

// A checkpoint removed or lost with completed records beside it: the resume re-measured every
// phase from bring-up (each capture set aside) and the dry run said the run had stopped before
// its first phase (an outside review). Refused, exit 2, the records left as they are; a folder
// that holds only the record its first phase was writing still resumes from bring-up.
TEST(Campaign, RecordsWithoutTheirCheckpointAreADamagedFolder) {
  const std::string d = tmp("campaign-no-checkpoint");
  fs::create_directories(d);
  const std::string r = d + "/killed";
  ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", r, "--inject", "sigkill@150"}, r + "-io"),
            128 + SIGKILL);
  ASSERT_TRUE(fs::remove(r + "/checkpoint.json"));
  std::set<std::string> before;
  for (const auto& e : fs::recursive_directory_iterator(r)) before.insert(e.path().string());
  for (const bool dry : {true, false}) {
    std::vector<std::string> args = {"run", "--resume", r, "--yes"};
    if (dry) args.push_back("--dry-run");
    EXPECT_EQ(run(args, r + "-resume"), 2) << slurp(r + "-resume.stderr");
    EXPECT_NE(slurp(r + "-resume.stderr").find(r + "/checkpoint.json: missing, but the folder holds 13 records "
                                               "(captures/in-run-U10.cap, captures/run01-U10.cap, captures/run02-U20.cap, "
                                               "...): a run writes its checkpoint once its first phase completes"),
              std::string::npos)
        << slurp(r + "-resume.stderr");
  }
  std::set<std::string> after;
  for (const auto& e : fs::recursive_directory_iterator(r)) after.insert(e.path().string());
  EXPECT_EQ(before, after);  // nothing set aside, nothing written
  // Killed while the first phase recorded: one record, no checkpoint, resumed from bring-up.
  const std::string early = d + "/early";
  ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", early, "--inject", "sigkill@10"}, early + "-io"),
            128 + SIGKILL);
  ASSERT_FALSE(fs::exists(early + "/checkpoint.json"));
  EXPECT_EQ(run({"run", "--resume", early, "--yes", "--quiet"}, early + "-resume"), 0) << slurp(early + "-resume.stderr");
  EXPECT_TRUE(fs::exists(early + "/captures/run01-U10.cap.interrupted-1"));
}

// An injected sample loss (--inject drop@SEQ:COUNT) is part of the emulated device's history:
// run.json keeps it and the resume's replay sees it again, so the resumed passport is the
// uninterrupted run's (it differed in 17 values, and the warning blamed another build: a review).
TEST(Campaign, AnInjectedSampleLossIsRepeatedByTheResume) {
  const std::string d = tmp("campaign-drop");
  fs::create_directories(d);
  const Reference ref = uninterrupted(d, "ci", {"--inject", "drop@29000:10"});
  const std::string r = d + "/killed";
  ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", r, "--inject", "drop@29000:10", "--inject",
                 "sigkill@150"},
                r + "-io"),
            128 + SIGKILL);
  EXPECT_EQ(read_json(r + "/run.json")["faults"], json::array({"drop@29000:10"}));
  resume_and_compare(r, ref, "drop@29000:10 then sigkill@150");
  // The plant's figures say which part of its device time rebuilt it (a review: a resume that
  // measured nothing new reported the replay's samples as its own).
  EXPECT_NE(slurp(r + "/run.log").find("samples of them replayed the kept recordings"), std::string::npos);
}

// SIGINT and SIGTERM at random device times: exit 3, ABORTED naming the signal, the safe state
// in order, the measurements of completed phases kept; then the resume equals the
// uninterrupted run.
TEST(Campaign, SigintAndSigtermAtRandomPointsAbortSafelyAndResumeLosslessly) {
  const std::string d = tmp("campaign-signal");
  fs::create_directories(d);
  const Reference ref = uninterrupted(d, "ci");
  int k = 0;
  for (const double t : random_points(1302, 6, 0.0, kCiDeviceS)) {
    const std::string sig = k % 2 ? "sigterm" : "sigint", name = k % 2 ? "SIGTERM" : "SIGINT";
    const std::string r = d + "/s" + std::to_string(++k), what = sig + "@" + fmt_t(t);
    ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", r, "--inject", what}, r + "-io"), 3)
        << what << "\n" << slurp(r + "-io.stderr");
    const json p = read_json(r + "/passport.json");
    EXPECT_EQ(p["outcome"], "ABORTED") << what;
    EXPECT_NE(p["aborted_reason"].get<std::string>().find(name), std::string::npos) << what << p["aborted_reason"];
    expect_safe_state_in_order(slurp(r + "/run.log"), what);
    for (const auto& [n, v] : p["values"].items()) EXPECT_NE(v["outcome"], "FAIL") << what << ": " << n;
    // Everything measured before the signal is kept: the values equal the uninterrupted run's.
    for (const auto& [n, v] : p["values"].items()) {
      if (!v["value"].is_null()) {
        EXPECT_EQ(v["value"], ref.passport["values"][n]["value"]) << what << ": " << n;
      }
    }
    resume_and_compare(r, ref, what);
  }
}

// The e-stop line opened at random device times (through the emulated GPIO and the rig's
// e-stop logic): exit 3, ABORTED for the e-stop, the safe state in order; resumable.
TEST(Campaign, EstopAtRandomPointsAbortsSafely) {
  const std::string d = tmp("campaign-estop");
  fs::create_directories(d);
  // With a --serial: it travels over the emulated CAN link (its length shifts the device time
  // of everything after bring-up), and the resume takes it from run.json.
  const Reference ref = uninterrupted(d, "ci", {"--serial", "EMU-ESTOP-7"});
  int k = 0;
  for (const double t : random_points(1303, 4, 0.0, kCiDeviceS)) {
    const std::string r = d + "/e" + std::to_string(++k), what = "estop@" + fmt_t(t);
    ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--serial", "EMU-ESTOP-7", "--out", r, "--inject",
                   what},
                  r + "-io"),
              3)
        << what << "\n" << slurp(r + "-io.stderr");
    const json p = read_json(r + "/passport.json");
    EXPECT_EQ(p["outcome"], "ABORTED") << what;
    EXPECT_NE(p["aborted_reason"].get<std::string>().find("e-stop"), std::string::npos) << what << p["aborted_reason"];
    expect_safe_state_in_order(slurp(r + "/run.log"), what);
    resume_and_compare(r, ref, what);
  }
}

// Late signals: SIGINT or SIGTERM after the last phase (before the passport is written) still
// end the run ABORTED with exit 3, the measurements kept. Every phase is in its checkpoint but
// the run has no verdict: a resume measures nothing again (the loop test's records are kept, as
// the captures are), computes every value again from the kept records and writes the
// uninterrupted run's passport; after that the run is complete and a further resume is refused,
// its passport left as it is. A loop-test.csv changed since it was recorded is refused; a
// checkpoint of the version that kept only the loop's figures runs the loop test again.
TEST(Campaign, LateSignalsAfterTheLastPhaseStillAbort) {
  const std::string d = tmp("campaign-late");
  fs::create_directories(d);
  const Reference ref = uninterrupted(d, "ci");
  for (const std::string sig : {"sigint", "sigterm"}) {
    const std::string r = d + "/" + sig, what = sig + "@end";
    ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", r, "--inject", what}, r + "-io"), 3)
        << what << "\n" << slurp(r + "-io.stderr");
    const json p = read_json(r + "/passport.json");
    EXPECT_EQ(p["outcome"], "ABORTED");
    const std::string name = sig == "sigint" ? "SIGINT" : "SIGTERM";
    EXPECT_NE(p["aborted_reason"].get<std::string>().find("after the last phase: " + name), std::string::npos)
        << p["aborted_reason"];
    for (const auto& [n, v] : p["values"].items()) EXPECT_EQ(v["value"], ref.passport["values"][n]["value"]) << n;
    const std::string log = slurp(r + "/run.log");
    expect_safe_state_in_order(log, what);
    EXPECT_NE(log.find("outcome ABORTED (exit 3)"), std::string::npos) << log;
    // The plan says what the resume does.
    ASSERT_EQ(run({"run", "--resume", r, "--dry-run"}, r + "-plan"), 0) << slurp(r + "-plan.stderr");
    const std::string plan = slurp(r + "-plan.stdout");
    EXPECT_NE(plan.find("still to run: nothing"), std::string::npos) << plan;
    EXPECT_NE(plan.find("computed again from the kept records: bias, in-run-b, allan, loop-figures"), std::string::npos)
        << plan;
    const std::string records = slurp(r + "/loop-test.csv");
    ASSERT_FALSE(records.empty());
    resume_and_compare(r, ref, what);
    const std::string tail = slurp(r + "/run.log").substr(log.size());
    EXPECT_EQ(tail.find("phase loop start"), std::string::npos) << "measured once: " << tail;
    EXPECT_EQ(slurp(r + "/loop-test.csv"), records);
    const json q = read_json(r + "/passport.json");
    for (const auto& ph : q["phases"]) {
      const bool again = ph["id"] == "bias" || ph["id"] == "in-run-b" || ph["id"] == "allan" || ph["id"] == "loop-figures";
      EXPECT_EQ(ph["status"], again ? "done" : "skipped") << ph;
    }
    const std::string after = slurp(r + "/passport.json");
    EXPECT_EQ(run({"run", "--resume", r, "--yes", "--no-history"}, r + "-again"), 2);
    EXPECT_NE(slurp(r + "-again.stderr").find("the run is complete"), std::string::npos) << slurp(r + "-again.stderr");
    EXPECT_EQ(slurp(r + "/passport.json"), after) << "a final passport is left as it was";
  }
  // The whole run as a kill after its last checkpoint leaves it (no passport), named `name`;
  // `edit` changes its checkpoint.
  auto killed_at_the_end = [&](const std::string& name, const std::function<void(json&)>& edit) {
    const std::string f = d + "/" + name;
    fs::copy(d + "/whole", f, fs::copy_options::recursive);
    fs::remove(f + "/passport.json");
    json cp = read_json(f + "/checkpoint.json");
    edit(cp);
    std::ofstream(f + "/checkpoint.json") << cp.dump(1);
    return f;
  };
  // Killed after the last checkpoint, before the passport was written: the same; the loop's
  // values edited in the checkpoint (the review's finding: a finished run's resume read them
  // back) are computed again, so the edit reaches nothing.
  const std::string k = killed_at_the_end("no-passport", [](json& cp) {
    for (const char* v : {"bandwidth_0p5", "settling_time"}) cp["values"][v]["value"] = 1.0;
  });
  resume_and_compare(k, ref, "no passport");
  // The loop test's records changed since they were recorded: refused before any device opens,
  // naming the field and the file; the checkpoint is kept as it was.
  const std::string e = killed_at_the_end("edited-records", [](json&) {});
  std::string csv = slurp(e + "/loop-test.csv");
  csv.replace(csv.rfind(',') + 1, 1, "9");
  std::ofstream(e + "/loop-test.csv", std::ios::binary) << csv;
  const std::string cp_before = slurp(e + "/checkpoint.json");
  EXPECT_EQ(run({"run", "--resume", e, "--yes", "--no-history"}, e + "-io"), 2);
  const std::string err = slurp(e + "-io.stderr");
  EXPECT_NE(err.find("state.loop_test.crc32: "), std::string::npos) << err;
  EXPECT_NE(err.find(e + "/loop-test.csv"), std::string::npos) << err;
  EXPECT_EQ(slurp(e + "/checkpoint.json"), cp_before);
  // The checkpoint's description of the records must be what the file states: a saturated step
  // (no figures, a FAIL) edited out of the checkpoint is refused too.
  const std::string s =
      killed_at_the_end("edited-state", [](json& cp) { cp["state"]["loop_test"]["saturated"][0] = true; });
  EXPECT_EQ(run({"run", "--resume", s, "--yes", "--no-history"}, s + "-io"), 2);
  EXPECT_NE(slurp(s + "-io.stderr").find("state.loop_test: " + s + "/loop-test.csv:3: the file states the loop saturated in steps 'none'; the loop test recorded '1'"),
            std::string::npos)
      << slurp(s + "-io.stderr");
  // A loop test marked "not supported" in a folder that holds its records (with a hardware
  // file's [dut.design], the design model's figures would stand in for the measured ones).
  const std::string n = killed_at_the_end("edited-supported", [](json& cp) {
    cp["state"]["loop_test"] = {{"supported", false}, {"reason", "no loop test"}};
  });
  EXPECT_EQ(run({"run", "--resume", n, "--yes", "--no-history"}, n + "-io"), 2);
  EXPECT_NE(slurp(n + "-io.stderr").find("state.loop_test.supported: false, but " + n + "/loop-test.csv holds"),
            std::string::npos)
      << slurp(n + "-io.stderr");
  // A checkpoint of the version before the records were kept: `loop` completed, the figures in
  // the state and no record of the test. Its figures are not taken: the loop test runs again.
  ASSERT_EQ(read_json(d + "/whole/checkpoint.json")["completed"].back(), "loop-figures");
  json old_cp;
  const std::string o = killed_at_the_end("older-checkpoint", [&old_cp](json& cp) {
    cp["completed"].erase(cp["completed"].size() - 1);
    cp["state"].erase("loop_test");
    for (const char* v : {"bandwidth_0p5", "settling_time"}) cp["values"][v]["value"] = 1.0;
    old_cp = cp;
  });
  fs::remove(o + "/loop-test.csv");
  resume_and_compare(o, ref, "older checkpoint");
  const std::string olog = slurp(o + "/run.log");
  EXPECT_NE(olog.find("phase loop: the checkpoint keeps no record of it"), std::string::npos) << olog;
  EXPECT_EQ(slurp(o + "/loop-test.csv"), slurp(d + "/whole/loop-test.csv")) << "measured again, as the run would have";
  // The same older checkpoint beside a final passport: the run is complete, whatever its phase
  // count says (a review's finding: it was measured again and its FAIL or PASS overwritten).
  const std::string f = d + "/older-finished";
  fs::copy(d + "/whole", f, fs::copy_options::recursive);
  // Its values are what that run measured, as its passport gives them (a passport whose values
  // its checkpoint does not hold is another run's: RigCli.AnotherRunsPassportInAStoppedRunsFolder...).
  old_cp["values"] = read_json(d + "/whole/checkpoint.json")["values"];
  std::ofstream(f + "/checkpoint.json") << old_cp.dump(1);
  const std::string final_passport = slurp(f + "/passport.json");
  for (const bool dry : {true, false}) {
    std::vector<std::string> args = {"run", "--resume", f, "--yes", "--no-history"};
    if (dry) args.push_back("--dry-run");
    EXPECT_EQ(run(args, f + "-io"), 2) << dry;
    EXPECT_NE(slurp(f + "-io.stderr").find("the run is complete (its passport says PASS)"), std::string::npos)
        << slurp(f + "-io.stderr");
  }
  EXPECT_EQ(slurp(f + "/passport.json"), final_passport);
  // A loop test recorded as not run (and no records): nothing is kept of it, the DUT is asked
  // again (here it runs the test: the uninterrupted run's results), never the checkpoint's reason.
  const std::string a = killed_at_the_end(
      "not-run", [](json& cp) { cp["state"]["loop_test"] = {{"supported", false}, {"reason", "edited"}}; });
  fs::remove(a + "/loop-test.csv");
  resume_and_compare(a, ref, "loop test recorded as not run");
  EXPECT_NE(slurp(a + "/run.log").find("phase loop start"), std::string::npos);
  // The device time is a time: a negative one is refused, naming it.
  const std::string t = killed_at_the_end("device-time", [](json& cp) { cp["state"]["device_time_s"] = -5; });
  EXPECT_EQ(run({"run", "--resume", t, "--yes", "--no-history"}, t + "-io"), 2);
  EXPECT_NE(slurp(t + "-io.stderr").find("state.device_time_s: expected a device time in [0, 1e9] s, found -5"),
            std::string::npos)
      << slurp(t + "-io.stderr");
  const std::string big = killed_at_the_end("device-time-big", [](json& cp) { cp["state"]["device_time_s"] = 1e300; });
  EXPECT_EQ(run({"run", "--resume", big, "--yes", "--no-history"}, big + "-io"), 2);
  EXPECT_NE(slurp(big + "-io.stderr").find("state.device_time_s: expected a device time in [0, 1e9] s, found 1e+300"),
            std::string::npos)
      << slurp(big + "-io.stderr");
}

// A resume continues the run it finds: the options that would change it are refused rather
// than ignored (before, --profile, --serial and --inject given with --resume were silently
// overridden by the run folder's), and a DUT other than the one the completed phases measured
// is refused at bring-up (before, the restored identity was overwritten, so a passport mixed
// two DUTs). Each refusal is exit 2 and leaves the checkpoint as it was: the right resume then
// completes the run.
TEST(Campaign, ResumeRefusesAnotherDutAndOptionsItWouldIgnore) {
  const std::string d = tmp("campaign-resume-guard");
  fs::create_directories(d);
  const std::string r = d + "/k";
  ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", r, "--inject", "sigkill@100"}, r + "-io"),
            128 + 9)
      << slurp(r + "-io.stderr");
  const std::string checkpoint = r + "/checkpoint.json", before = slurp(checkpoint);
  ASSERT_FALSE(before.empty());
  // The plan of the resume says what it keeps, computes again and still records.
  ASSERT_EQ(run({"run", "--resume", r, "--dry-run"}, r + "-plan"), 0) << slurp(r + "-plan.stderr");
  const std::string plan = slurp(r + "-plan.stdout");
  EXPECT_NE(plan.find("Resume: " + checkpoint + " checked with the records it names (captures, loop-test.csv); "),
            std::string::npos)
      << plan;
  EXPECT_NE(plan.find("  kept (not recorded again): run01-U10, "), std::string::npos) << plan;
  EXPECT_NE(plan.find("  still to run: "), std::string::npos) << plan;
  EXPECT_NE(plan.find(", loop, loop-figures\n"), std::string::npos) << plan;
  // A capture the kill left partial is named, with what the resume does with it (the plan said
  // only the rule: a technician's review). Killed between two recordings here: none.
  EXPECT_EQ(plan.find("left partial by the interruption"), std::string::npos) << plan;
  const std::string mid = d + "/mid";
  ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", mid, "--inject", "sigkill@107"}, mid + "-io"),
            128 + 9);
  ASSERT_EQ(run({"run", "--resume", mid, "--dry-run"}, mid + "-plan"), 0) << slurp(mid + "-plan.stderr");
  EXPECT_NE(slurp(mid + "-plan.stdout")
                .find("  left partial by the interruption: captures/run11-U10.cap (kept as "
                      "captures/run11-U10.cap.interrupted-N when its phase records again)\n"),
            std::string::npos)
      << slurp(mid + "-plan.stdout");
  EXPECT_NE(plan.find("Estimated duration of what is left: "), std::string::npos) << plan;
  const std::vector<std::vector<std::string>> refused = {{"--profile", "paper"},
                                                         {"--plant", "emulated"},
                                                         {"--out", d + "/elsewhere"},
                                                         {"--inject", "sigkill@200"},
                                                         {"--serial", "QPA-OTHER"}};
  for (const auto& extra : refused) {
    std::vector<std::string> args = {"run", "--resume", r, "--yes", "--no-history"};
    args.insert(args.end(), extra.begin(), extra.end());
    EXPECT_EQ(run(args, r + "-opt"), 2) << extra[0] << "\n" << slurp(r + "-opt.stderr");
    EXPECT_NE(slurp(r + "-opt.stderr").find(extra[0]), std::string::npos) << slurp(r + "-opt.stderr");
    EXPECT_EQ(slurp(checkpoint), before) << extra[0];
  }
  // Started without --serial, the run's DUT is the one that reported its serial: --serial naming
  // it guards the resume (a review found it refused), another is refused naming the run's.
  EXPECT_NE(slurp(r + "-opt.stderr").find("--serial QPA-OTHER: the run in " + r + " is of DUT 'EMU-QPA-0001'"),
            std::string::npos)
      << slurp(r + "-opt.stderr");
  EXPECT_EQ(run({"run", "--resume", r, "--dry-run", "--serial", "EMU-QPA-0001"}, r + "-guard"), 0)
      << slurp(r + "-guard.stderr");
  // A checkpoint whose DUT is not the one its captures were recorded from is refused before
  // any device opens, naming the first capture that says otherwise.
  json c = read_json(checkpoint);
  ASSERT_EQ(c["state"]["dut"]["serial"], "EMU-QPA-0001");
  c["state"]["dut"]["serial"] = "QPA-OTHER";
  std::ofstream(checkpoint) << c.dump();
  EXPECT_EQ(run({"run", "--resume", r, "--yes", "--no-history"}, r + "-state"), 2) << slurp(r + "-state.stderr");
  EXPECT_NE(slurp(r + "-state.stderr").find("state.runs.1.capture: " + r + "/captures/run01-U10.cap's header says "
                                            "serial 'EMU-QPA-0001', not 'QPA-OTHER'"),
            std::string::npos)
      << slurp(r + "-state.stderr");
  EXPECT_EQ(slurp(r + "/run.log").find("bring-up", slurp(r + "/run.log").rfind("run: profile")), std::string::npos)
      << "refused before bring-up";
  // Another DUT: the checkpoint and its captures say the completed phases measured QPA-OTHER,
  // the emulated DUT reports EMU-QPA-0001.
  auto captures_of = [&](const std::string& serial) {
    for (const auto& [i, run] : c["state"]["runs"].items())
      rewrite_capture(r + "/" + run["capture"].get<std::string>(),
                      [&](rig::capture::Header& h, std::vector<rig::Sample>&) { h.serial = serial; });
  };
  captures_of("QPA-OTHER");
  EXPECT_EQ(run({"run", "--resume", r, "--yes", "--no-history"}, r + "-dut"), 2) << slurp(r + "-dut.stderr");
  EXPECT_NE(slurp(r + "-dut.stderr").find("DUT reports serial 'EMU-QPA-0001', but the run being resumed measured "
                                          "'QPA-OTHER'"),
            std::string::npos)
      << slurp(r + "-dut.stderr");
  EXPECT_EQ(read_json(checkpoint)["completed"], json::parse(before)["completed"]) << "the completed phases are kept";
  c["state"]["dut"]["serial"] = "EMU-QPA-0001";
  std::ofstream(checkpoint) << c.dump();
  captures_of("EMU-QPA-0001");
  EXPECT_EQ(run({"run", "--resume", r, "--yes", "--no-history"}, r + "-ok"), 0) << slurp(r + "-ok.stderr");
  EXPECT_EQ(read_json(r + "/passport.json")["outcome"], "PASS");
}

// A SIGTERM from outside (a service manager stopping rig), not injected: taken like SIGINT.
// (Wall-time points are not drawn at random here: whether a signal lands before or after the
// passport is final would then depend on the machine's load; the late points are the
// sigint@end / sigterm@end cases above.)
TEST(Campaign, ExternalSigtermIsTakenLikeSigint) {
  const std::string d = tmp("campaign-external");
  fs::create_directories(d);
  const std::string r = d + "/x";
  Child c = spawn({"run", "--profile", "ci", "--yes", "--no-history", "--out", r}, r + "-io");
  ASSERT_TRUE(wait_for_file(c, r + "/captures/in-run-U10.cap")) << slurp(r + "-io.stderr");
  ::kill(c.pid, SIGTERM);
  ASSERT_EQ(wait_exit(c), 3) << slurp(r + "-io.stderr");
  const json p = read_json(r + "/passport.json");
  EXPECT_EQ(p["outcome"], "ABORTED");
  EXPECT_NE(p["aborted_reason"].get<std::string>().find("SIGTERM"), std::string::npos) << p["aborted_reason"];
  expect_safe_state_in_order(slurp(r + "/run.log"), "external SIGTERM");
}

// Two paper runs (the issue's profile): killed at a random point of its 114 min of device
// time, resumed, and equal to the uninterrupted paper run bit for bit.
TEST(Campaign, PaperSigkillThenResumeEqualsTheUninterruptedRun) {
  const std::string d = tmp("campaign-paper");
  fs::create_directories(d);
  const Reference ref = uninterrupted(d, "paper");
  EXPECT_EQ(ref.passport["outcome"], "PASS");
  const double t = random_points(1305, 1, 1500.0, kPaperDeviceS)[0];
  const std::string r = d + "/k", what = "sigkill@" + fmt_t(t);
  EXPECT_EQ(run({"run", "--profile", "paper", "--yes", "--no-history", "--out", r, "--inject", what}, r + "-io"),
            128 + SIGKILL)
      << slurp(r + "-io.stderr");
  resume_and_compare(r, ref, what);
}

// The damaged-checkpoint set beyond the fields RigCli.DamagedCheckpointsAreRefusedNamingFileAndField
// covers: a checkpoint cut mid-write, of another schema, with phases out of order, of another
// profile, naming a capture shorter than what it recorded: each exit 2 naming the checkpoint,
// never a passport. A stale checkpoint.json.tmp (a kill during the atomic write) is ignored.
TEST(Campaign, DamagedCheckpointSet) {
  const std::string d = tmp("campaign-damaged");
  fs::create_directories(d);
  const Reference ref = uninterrupted(d, "ci");
  const std::string base = d + "/base";
  ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", base, "--inject", "sigkill@180"},
                d + "/base-io"),
            128 + SIGKILL);
  const std::string good = slurp(base + "/checkpoint.json");
  const json cp = json::parse(good);
  ASSERT_TRUE(cp["state"].contains("in_run")) << "killed after the in-run capture";
  int k = 0;
  auto copy = [&] {
    const std::string f = d + "/f" + std::to_string(++k);
    fs::copy(base, f, fs::copy_options::recursive);
    return f;
  };
  auto refused = [&](const std::string& f, const std::string& says) {
    EXPECT_EQ(run({"run", "--resume", f, "--dry-run"}, f + "-dry"), 2) << says << ": the plan did not check it";
    EXPECT_NE(slurp(f + "-dry.stderr").find(says), std::string::npos) << slurp(f + "-dry.stderr");
    EXPECT_EQ(run({"run", "--resume", f, "--yes", "--no-history"}, f + "-io"), 2) << says;
    const std::string err = slurp(f + "-io.stderr");
    EXPECT_NE(err.find(f + "/checkpoint.json: "), std::string::npos) << err;
    EXPECT_NE(err.find(says), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(f + "/passport.json")) << says;
  };
  {
    const std::string f = copy();
    std::ofstream(f + "/checkpoint.json") << good.substr(0, good.size() / 2);  // cut mid-write
    refused(f, "unreadable checkpoint");
  }
  {
    // A key twice in one object: refused, not read at its last (a review: values of the second
    // "completed" or "values" would have been the resumed run's).
    const std::string f = copy();
    std::ofstream(f + "/checkpoint.json") << "{\"completed\": []," << good.substr(good.find('{') + 1);
    refused(f, "unreadable checkpoint: key 'completed' appears twice in one object");
  }
  {
    // run.json the same: its second "plant" or "serial" was the resume's.
    const std::string f = copy();
    const std::string inv = slurp(f + "/run.json");
    std::ofstream(f + "/run.json") << "{\"plant\": \"hardware\"," << inv.substr(inv.find('{') + 1);
    EXPECT_EQ(run({"run", "--resume", f, "--yes", "--no-history"}, f + "-io"), 2);
    EXPECT_NE(slurp(f + "-io.stderr").find(f + "/run.json: unreadable: key 'plant' appears twice in one object"),
              std::string::npos)
        << slurp(f + "-io.stderr");
    EXPECT_FALSE(fs::exists(f + "/passport.json"));
  }
  {
    json j = cp;
    j["schema"] = "rig.checkpoint/9";
    const std::string f = copy();
    std::ofstream(f + "/checkpoint.json") << j.dump();
    refused(f, "schema");
  }
  {
    json j = cp;
    std::swap(j["completed"][0], j["completed"][1]);
    const std::string f = copy();
    std::ofstream(f + "/checkpoint.json") << j.dump();
    refused(f, "completed[0]: \"run02-U20\" is not phase 1 (run01-U10)");
  }
  {
    json j = cp;
    j["identity"]["profile_digest"] = "0000";
    const std::string f = copy();
    std::ofstream(f + "/checkpoint.json") << j.dump();
    // The profile's own digest is not printed (a review: it made an edited profile's resume pass).
    refused(f, "identity.profile_digest: \"0000\", not this profile's: ");
    refused(f, "different profile, serial or plant (" + f + "/profile.toml, which a resume reads, is not the profile the "
               "run started with: edited since?); start a new run instead");
  }
  {
    const std::string f = copy();
    const std::string cap = f + "/" + cp["state"]["in_run"]["capture"].get<std::string>();
    fs::resize_file(cap, fs::file_size(cap) / 2);
    refused(f, "state.in_run");
  }
  {  // A run's mean that its capture does not give: refused, naming both.
    json j = cp;
    j["state"]["runs"]["3"]["mean_g"] = j["state"]["runs"]["3"]["mean_g"].get<double>() * (1 + 1e-15);
    const std::string f = copy();
    std::ofstream(f + "/checkpoint.json") << j.dump();
    refused(f, "state.runs.3.mean_g: ");
    refused(f, " contradicts " + f + "/captures/run03-U10.cap, whose samples' mean is ");
  }
  // A checkpoint edited to point a record at another recording, or at a recording cut, emptied,
  // reordered or of no DUT (session 15's review turned each into a PASS of a failing DUT before):
  // each is refused naming the field, through --dry-run too.
  {  // run 2 (U20) given run 1's (U10) record: the bias would come from U10 runs only
    json j = cp;
    j["state"]["runs"]["2"] = j["state"]["runs"]["1"];
    j["state"]["runs"]["2"]["index"] = 2;
    j["state"]["runs"]["2"]["orientation"] = "U20";
    const std::string f = copy();
    std::ofstream(f + "/checkpoint.json") << j.dump();
    refused(f, "state.runs.2.capture: \"captures/run01-U10.cap\" is not this recording's capture "
               "(captures/run02-U20.cap)");
  }
  {  // run 1's capture copied over run 3's file (same orientation and length), the mean with it
    json j = cp;
    j["state"]["runs"]["3"]["mean_g"] = j["state"]["runs"]["1"]["mean_g"];
    j["state"]["runs"]["3"]["mean_y_g"] = j["state"]["runs"]["1"]["mean_y_g"];
    const std::string f = copy();
    fs::copy_file(f + "/captures/run01-U10.cap", f + "/captures/run03-U10.cap", fs::copy_options::overwrite_existing);
    std::ofstream(f + "/checkpoint.json") << j.dump();
    refused(f, "state.runs.3.capture: " + f + "/captures/run03-U10.cap's header says phase 'run01-U10', not "
               "'run03-U10'");
  }
  {  // a run emptied to its header, n = 0 and the mean 0
    json j = cp;
    j["state"]["runs"]["2"]["n"] = 0;
    j["state"]["runs"]["2"]["mean_g"] = 0.0;
    const std::string f = copy();
    std::ofstream(f + "/checkpoint.json") << j.dump();
    refused(f, "state.runs.2.n: 0 samples, but a recording of 2 s at 1000 Hz holds 2000");
  }
  {  // the in-run capture without its end marker (its writer did not close it)
    const std::string f = copy();
    const std::string cap = f + "/" + cp["state"]["in_run"]["capture"].get<std::string>();
    fs::resize_file(cap, fs::file_size(cap) - 4);
    refused(f, "state.in_run.capture: ");
    refused(f, "(a completed recording's writer closed it)");
  }
  {  // the in-run capture's halves swapped (every block intact), the loss raised to cover it
    json j = cp;
    const std::string f = copy();
    const std::string cap = f + "/" + j["state"]["in_run"]["capture"].get<std::string>();
    rewrite_capture(cap, [](rig::capture::Header&, std::vector<rig::Sample>& s) {
      std::rotate(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(s.size() / 2), s.end());
    });
    refused(f, "state.in_run.capture: " + cap + "'s sequence counter goes back at sample 20000");
    j["state"]["in_run"]["lost"] = 4294967295LL;
    std::ofstream(f + "/checkpoint.json") << j.dump();
    refused(f, "state.in_run.lost: 4294967295 exceeds the profile's max_lost_samples (0)");
  }
  {  // the DUT's identity deleted: the captures' serial would go unchecked
    json j = cp;
    j["state"].erase("dut");
    const std::string f = copy();
    std::ofstream(f + "/checkpoint.json") << j.dump();
    refused(f, "state.dut: missing, but recordings are marked completed");
  }
  {  // parts no completed phase wrote: a 13th run, a raw capture before the raw phase
    json j = cp;
    j["state"]["runs"]["13"] = j["state"]["runs"]["12"];
    j["state"]["runs"]["13"]["index"] = 13;
    std::string f = copy();
    std::ofstream(f + "/checkpoint.json") << j.dump();
    refused(f, "state.runs.13: present, but no completed phase records it");
    j = cp;
    j["state"]["raw"] = j["state"]["in_run"];
    j["state"]["raw"].erase("blocks");
    f = copy();
    std::ofstream(f + "/checkpoint.json") << j.dump();
    refused(f, "state.raw: present, but phase 'raw' that writes it is not completed");
  }
  {  // Keys this version does not write, attempts no kept recording took (a review: both were
     // accepted, and the attempts copied into analysis.json).
    json j = cp;
    j["state"]["bogus"] = 1;
    std::string f = copy();
    std::ofstream(f + "/checkpoint.json") << j.dump();
    refused(f, "state.bogus: not a key of a checkpoint (edited, or written by another version of rig?)");
    for (const int attempts : {0, 99}) {
      j = cp;
      j["state"]["runs"]["3"]["attempts"] = attempts;
      f = copy();
      std::ofstream(f + "/checkpoint.json") << j.dump();
      refused(f, "state.runs.3.attempts: " + std::to_string(attempts) + ", but a kept recording took 1 to 2 attempts");
    }
    j = cp;
    j["state"]["runs"]["3"]["attempts"] = 4294967297ull;  // 2^32 + 1: it wrapped to 1 and was accepted
    f = copy();
    std::ofstream(f + "/checkpoint.json") << j.dump();
    refused(f, "state.runs.3.attempts: expected a number of attempts");
    for (const char* where : {"top", "bias", "block", "skipped", "value"}) {  // the review: unknown keys there were accepted
      j = cp;
      const std::string w = where;
      if (w == "top") j["bogus"] = 1;
      if (w == "bias") j["state"]["bias"]["bogus"] = 1;
      if (w == "block") j["state"]["in_run"]["blocks"][0]["bogus"] = 1;
      if (w == "skipped") j["state"]["dut"]["skipped"] = json::array({{{"step", "s"}, {"reason", "r"}, {"bogus", 1}}});
      if (w == "value") j["values"]["bias"]["bogus"] = 1;
      f = copy();
      std::ofstream(f + "/checkpoint.json") << j.dump();
      refused(f, "bogus: not a key of a checkpoint");
    }
    // What the log is missing is a string (a resume refuses a folder whose checkpoint records it).
    j = cp;
    j["log_missing_lines"] = 1;
    f = copy();
    std::ofstream(f + "/checkpoint.json") << j.dump();
    refused(f, "log_missing_lines: expected a string");
    j = cp;
    j["log_missing_lines"] = "run.log is missing lines: the disk refused 3 line(s)";
    f = copy();
    std::ofstream(f + "/checkpoint.json") << j.dump();
    for (const bool dry : {true, false}) {  // not a damage: the folder's own word that its log is short
      const std::string io = f + (dry ? "-dry" : "-io");
      EXPECT_EQ(run({"run", "--resume", f, dry ? "--dry-run" : "--yes", "--no-history"}, io), 2);
      EXPECT_NE(slurp(io + ".stderr").find(f + ": its checkpoint records that run.log is missing lines: the disk "
                                               "refused 3 line(s); no resume gives those lines back"),
                std::string::npos)
          << slurp(io + ".stderr");
    }
    EXPECT_FALSE(fs::exists(f + "/passport.json"));
  }
  {  // A capture whose sequence counter skips samples the record does not count as lost.
    json j = cp;
    const std::string f = copy();
    const std::string cap = f + "/" + j["state"]["in_run"]["capture"].get<std::string>();
    rewrite_capture(cap, [](rig::capture::Header&, std::vector<rig::Sample>& s) {
      for (std::size_t i = s.size() / 2; i < s.size(); ++i) s[i].seq += 5;
    });
    refused(f, "state.in_run.lost: 0 samples lost in 0 gap(s) recorded, but " + cap +
                   "'s sequence counter skips 5 in 1");
  }
  {  // A checkpoint whose recordings this plant does not reproduce (here a run's capture and
     // mean edited together; in practice one written by another build): the resume goes on,
     // and says so.
    json j = cp;
    const std::string f = copy();
    rewrite_capture(f + "/captures/run03-U10.cap", [&](rig::capture::Header&, std::vector<rig::Sample>& s) {
      s[7].x_g += 1e-6f;
      j["state"]["runs"]["3"]["mean_g"] = mean_x(s);
    });
    std::ofstream(f + "/checkpoint.json") << j.dump();
    EXPECT_EQ(run({"run", "--resume", f, "--yes", "--no-history"}, f + "-io"), 0) << slurp(f + "-io.stderr");
    const std::string err = slurp(f + "-io.stderr");
    EXPECT_NE(err.find("fast-forward: the replay does not reproduce " + f + "/checkpoint.json: state.runs.3.mean_g"),
              std::string::npos)
        << err;
    EXPECT_NE(err.find("the resumed passport will differ"), std::string::npos) << err;
  }
  {  // A kill between writing checkpoint.json.tmp and its rename: the previous checkpoint stands.
    const std::string f = copy();
    std::ofstream(f + "/checkpoint.json.tmp") << good.substr(0, 100);
    resume_and_compare(f, ref, "stale checkpoint.json.tmp");
  }
}

// Every passport value is computed from the kept captures, never read back from checkpoint.json:
// a checkpoint whose values and derived state were edited to pass (the filtered RMS below its
// limit, the best accuracy class, a null bias, GOST B and the analysis replaced) and resumed
// inside the loop phase gives the failing run's passport and analysis.json bit for bit, exit 1.
// Before, the values of completed phases were taken as written: the edited checkpoint PASSed.
TEST(Campaign, AResumeComputesEveryValueFromTheKeptCaptures) {
  const std::string d = tmp("campaign-recompute");
  fs::create_directories(d);
  std::ofstream(d + "/strict.toml") << "base = \"ci\"\n[profile]\nname = \"t-strict\"\n[limits]\nrms_filtered = [0.0, 1.0e-9]\n"
                                       "[[classes]]\nname = \"impossible\"\nmax_b_g = 1.0e-12\n";
  std::vector<std::string> args = {"run", "--profile", d + "/strict.toml", "--yes", "--no-history", "--out", d + "/whole"};
  ASSERT_EQ(run(args, d + "/whole-io"), 1) << slurp(d + "/whole-io.stderr");
  const Reference ref{read_json(d + "/whole/passport.json"), read_json(d + "/whole/analysis.json")};
  ASSERT_EQ(ref.passport["values"]["rms_filtered"]["outcome"], "FAIL");
  ASSERT_EQ(ref.passport["values"]["accuracy_class"]["outcome"], "FAIL");

  const std::string r = d + "/k", what = "sigkill@" + fmt_t(kCiLoopPhaseS);
  args = {"run", "--profile", d + "/strict.toml", "--yes", "--no-history", "--out", r, "--inject", what};
  ASSERT_EQ(run(args, r + "-io"), 128 + SIGKILL) << slurp(r + "-io.stderr");
  json cp = read_json(r + "/checkpoint.json");
  ASSERT_EQ(cp["completed"].back(), "allan") << "killed inside the loop phase";
  cp["values"]["rms_filtered"]["value"] = 1e-12;
  cp["values"]["rms_unfiltered"]["value"] = 1e-12;
  cp["values"]["accuracy_class"]["value"] = 1;
  cp["values"]["accuracy_class"]["reason"] = "precision";
  cp["values"]["bias"]["value"] = nullptr;
  cp["values"]["k"]["value"] = 1e-9;
  cp["state"]["bias"]["bias"] = 0.0;
  for (auto& b : cp["state"]["in_run"]["blocks"]) b["b_g"] = 1e-13;
  cp["state"]["analysis"] = json::object({{"edited", true}});
  std::ofstream(r + "/checkpoint.json") << cp.dump();
  EXPECT_EQ(run({"run", "--resume", r, "--yes", "--no-history"}, r + "-resume"), 1) << slurp(r + "-resume.stderr");
  const json p = read_json(r + "/passport.json");
  EXPECT_EQ(without_session_fields(p), without_session_fields(ref.passport))
      << "the resumed passport is not the one its captures give";
  EXPECT_EQ(read_json(r + "/analysis.json"), ref.analysis);
  for (const auto& ph : p["phases"])
    if (ph["id"] == "bias" || ph["id"] == "in-run-b" || ph["id"] == "allan") {
      EXPECT_EQ(ph["status"], "done") << ph.dump();
    }
}

namespace {

std::string write_key(const std::string& path, char fill, unsigned mode = 0600) {
  std::ofstream(path, std::ios::binary) << std::string(32, fill);
  fs::permissions(path, static_cast<fs::perms>(mode), fs::perm_options::replace);
  return path;
}

}  // namespace

// A run killed while it started (after its run.json, or in its first seal) left a folder that was
// neither resumable (with the station's key: never sealed) nor reusable (a review). A new run
// takes over a folder that holds only the files of such a start; one whose log began is an
// earlier run still, resumed and never taken over.
TEST(Campaign, AFolderWithOnlyAStoppedStartIsTakenOverByANewRun) {
  const std::string d = tmp("campaign-start-only");
  fs::create_directories(d);
  const std::string key = write_key(d + "/station.key", 'k');
  (void)uninterrupted(d, "ci");
  // Killed after its run.json (before the seal and the log), a profile.toml staged beside.
  const std::string after = d + "/after-run-json";
  fs::create_directories(after);
  fs::copy_file(d + "/whole/run.json", after + "/run.json");
  fs::copy_file(d + "/whole/profile.toml", after + "/profile.toml");
  std::ofstream(after + "/profile.toml.tmp") << "# half";
  ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", after}, after + "-io"), 0)
      << slurp(after + "-io.stderr");
  EXPECT_NE(slurp(after + "-io.stderr").find("holds only the start of an earlier run"), std::string::npos)
      << slurp(after + "-io.stderr");
  EXPECT_EQ(read_json(after + "/passport.json")["outcome"], "PASS");
  EXPECT_FALSE(fs::exists(after + "/profile.toml.tmp"));
  // Killed in its first seal (another profile's start, the seal staged): a sealed run takes it
  // over, and the station's key verifies the folder.
  const std::string in_seal = d + "/in-first-seal";
  fs::create_directories(in_seal);
  fs::copy_file(d + "/whole/run.json", in_seal + "/run.json");
  std::ofstream(in_seal + "/profile.toml") << "# an earlier start's profile\n";
  std::ofstream(in_seal + "/seal.json.tmp") << "{";
  std::ofstream(in_seal + "/run.log");  // opened, killed before its first line
  ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--dry-run", "--out", in_seal}, in_seal + "-dry"), 0)
      << slurp(in_seal + "-dry.stderr");
  EXPECT_NE(slurp(in_seal + "-dry.stdout").find("Note: " + in_seal + " holds only the start of an earlier run"),
            std::string::npos)
      << slurp(in_seal + "-dry.stdout");
  ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--seal-key", key, "--out", in_seal}, in_seal + "-io"),
            0)
      << slurp(in_seal + "-io.stderr");
  EXPECT_FALSE(fs::exists(in_seal + "/seal.json.tmp"));
  // On the record too, not only on the terminal (its run.json was replaced).
  EXPECT_NE(slurp(in_seal + "/run.log").find("holds only the start of an earlier run"), std::string::npos);
  EXPECT_EQ(run({"verify", in_seal, "--seal-key", key}, in_seal + "-verify"), 0) << slurp(in_seal + "-verify.stdout");
  EXPECT_EQ(read_json(in_seal + "/passport.json")["values"], read_json(d + "/whole/passport.json")["values"]);
  // A run.json that is not the rig's is not a start it can take over.
  const std::string foreign = d + "/foreign";
  fs::create_directories(foreign);
  std::ofstream(foreign + "/run.json") << R"({"software": "someone else's"})";
  EXPECT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", foreign}, foreign + "-io"), 2);
  // A start whose log began is a run: resumed, not taken over.
  const std::string logged = d + "/logged";
  fs::create_directories(logged);
  fs::copy_file(d + "/whole/run.json", logged + "/run.json");
  fs::copy_file(d + "/whole/profile.toml", logged + "/profile.toml");
  std::ofstream(logged + "/run.log") << "2026-12-06T00:00:00.000Z info  rig run: ...\n";
  EXPECT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", logged}, logged + "-io"), 2);
  EXPECT_NE(slurp(logged + "-io.stderr").find("holds an earlier run (run.json): use --resume"), std::string::npos)
      << slurp(logged + "-io.stderr");
}

// The station's seal (docs/seal.md): a sealed run verifies; an edited passport does not; a
// sealed run resumes only with its key and only while the folder is as sealed, so the review's
// F7 (profile.toml's limits loosened and its digest copied into the checkpoint) is refused; a
// stop between a new seal and its checkpoint leaves seal.prev.json, which holds.
TEST(Campaign, SealedRunFolders) {
  const std::string d = tmp("campaign-seal");
  fs::create_directories(d);
  const std::string key = write_key(d + "/station.key", 'k'), other = write_key(d + "/other.key", 'o');
  const Reference ref = uninterrupted(d, "ci");

  // An uninterrupted sealed run: verified; the same passport as without a seal.
  const std::string whole = d + "/sealed";
  ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", whole, "--seal-key", key}, whole + "-io"), 0)
      << slurp(whole + "-io.stderr");
  EXPECT_EQ(without_session_fields(read_json(whole + "/passport.json")), without_session_fields(ref.passport));
  EXPECT_FALSE(fs::exists(whole + "/seal.prev.json"));
  ASSERT_EQ(run({"verify", whole, "--seal-key", key}, whole + "-verify"), 0) << slurp(whole + "-verify.stdout");
  EXPECT_NE(slurp(whole + "-verify.stdout").find("ok       captures/raw-U10.cap"), std::string::npos);
  EXPECT_NE(slurp(whole + "-verify.stdout").find("ok       passport.json"), std::string::npos);
  std::ofstream(whole + "/captures/extra.cap") << "x";
  EXPECT_EQ(run({"verify", whole, "--seal-key", key}, whole + "-extra"), 1);
  EXPECT_NE(slurp(whole + "-extra.stdout").find("captures/extra.cap: not sealed (added after the seal)"),
            std::string::npos)
      << slurp(whole + "-extra.stdout");
  fs::remove(whole + "/captures/extra.cap");
  // A hidden file is outside what a seal covers: the folder still verifies, and the file is named.
  std::ofstream(whole + "/captures/.note") << "x";
  EXPECT_EQ(run({"verify", whole, "--seal-key", key}, whole + "-hidden"), 0) << slurp(whole + "-hidden.stdout");
  EXPECT_NE(slurp(whole + "-hidden.stdout").find("the verdict does not rest on them): captures/.note\n"),
            std::string::npos)
      << slurp(whole + "-hidden.stdout");
  EXPECT_EQ(slurp(whole + "-verify.stdout").find("not covered by the seal"), std::string::npos)
      << slurp(whole + "-verify.stdout");
  fs::remove(whole + "/captures/.note");
  {
    // rig report on the folder writes the same page, and it still verifies; on a copy (an
    // archive) the page would name its new folder: the sealed page is kept, exit 2, unless
    // --force (a technician's review: the copy's seal broke, silently).
    ASSERT_EQ(run({"report", whole}, whole + "-report"), 0) << slurp(whole + "-report.stderr");
    ASSERT_EQ(run({"verify", whole, "--seal-key", key}, whole + "-reverify"), 0) << slurp(whole + "-reverify.stdout");
    const std::string copy = d + "/archived";
    fs::copy(whole, copy, fs::copy_options::recursive);
    const std::string page = slurp(copy + "/report.html");
    EXPECT_EQ(run({"report", copy}, copy + "-report"), 2);
    EXPECT_NE(slurp(copy + "-report.stderr").find("/archived/report.html, and the page written now differs from it"),
              std::string::npos)
        << slurp(copy + "-report.stderr");
    EXPECT_EQ(slurp(copy + "/report.html"), page);
    EXPECT_EQ(run({"verify", copy, "--seal-key", key}, copy + "-verify"), 0) << slurp(copy + "-verify.stdout");
    EXPECT_EQ(run({"report", copy, "--force"}, copy + "-force"), 0) << slurp(copy + "-force.stderr");
    EXPECT_NE(slurp(copy + "/report.html"), page);
    EXPECT_EQ(run({"verify", copy, "--seal-key", key}, copy + "-forced"), 1);
    EXPECT_NE(slurp(copy + "-forced.stdout").find("CHANGED  report.html"), std::string::npos)
        << slurp(copy + "-forced.stdout");
    // A seal.json that is no seal is named as such, not as sealing the page.
    const std::string damaged = d + "/archived-damaged";
    fs::copy(whole, damaged, fs::copy_options::recursive);
    std::ofstream(damaged + "/seal.json") << "{";
    EXPECT_EQ(run({"report", damaged}, damaged + "-report"), 2);
    EXPECT_NE(slurp(damaged + "-report.stderr").find("seal.json cannot be read as a seal (`rig verify` says why)"),
              std::string::npos)
        << slurp(damaged + "-report.stderr");
  }
  {
    // Loop-test records swapped in before the station sealed them (a review's finding: the
    // station seals the bytes it reads back; before, a swapped file verified as PASS): verify
    // holds them to the sealed checkpoint's CRC-32.
    const std::string swapped = d + "/swapped";
    fs::copy(whole, swapped, fs::copy_options::recursive);
    std::string csv = slurp(swapped + "/loop-test.csv");
    csv.replace(csv.rfind(',') + 1, 1, "9");
    std::ofstream(swapped + "/loop-test.csv", std::ios::binary) << csv;
    const json sealed = read_json(swapped + "/seal.json");
    std::vector<rig::seal::Entry> entries;
    for (const auto& [rel, mac] : sealed["files"].items()) entries.push_back({rel, "", false, ""});
    std::ofstream(swapped + "/seal.json")
        << rig::seal::make_seal(swapped, rig::seal::load_key(key), entries, sealed["outcome"].get<std::string>());
    EXPECT_EQ(run({"verify", swapped, "--seal-key", key}, swapped + "-verify"), 1);
    EXPECT_NE(slurp(swapped + "-verify.stdout").find("ok       loop-test.csv"), std::string::npos)
        << "sealed as swapped: " << slurp(swapped + "-verify.stdout");
    EXPECT_NE(slurp(swapped + "-verify.stdout")
                  .find("problem: loop-test.csv: not the records the checkpoint describes (state.loop_test.crc32: "),
              std::string::npos)
        << slurp(swapped + "-verify.stdout");
  }
  EXPECT_EQ(run({"verify", whole, "--seal-key", other}, whole + "-other"), 1);
  EXPECT_NE(slurp(whole + "-other.stdout").find("sealed with another key"), std::string::npos);
  {
    std::string p = slurp(whole + "/passport.json");
    p.replace(p.find("\"outcome\": \"PASS\""), 17, "\"outcome\": \"FAIL\"");
    std::ofstream(whole + "/passport.json") << p;
  }
  EXPECT_EQ(run({"verify", whole, "--seal-key", key}, whole + "-edited"), 1);
  EXPECT_NE(slurp(whole + "-edited.stdout").find("CHANGED  passport.json"), std::string::npos)
      << slurp(whole + "-edited.stdout");
  EXPECT_EQ(run({"verify", ref.passport["out_dir"].get<std::string>(), "--seal-key", key}, d + "/unsealed"), 1);
  EXPECT_NE(slurp(d + "/unsealed.stdout").find("the folder is not sealed"), std::string::npos);

  {
    // Stopped after its final seal, before its history row (.ending-pending, app/cmd_run.cpp):
    // the resume with the key records the row from the passport the seal vouches for, computing
    // nothing again, and the folder still verifies (the list is outside the seal); a passport
    // changed since is the sealed verdict's, refused as complete.
    const std::string sealed_h = d + "/sealed-h", db = d + "/sealed-h.sqlite";
    ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--db", "sqlite:" + db, "--out", sealed_h, "--seal-key", key},
                  sealed_h + "-io"),
              0)
        << slurp(sealed_h + "-io.stderr");
    std::ofstream(sealed_h + "/.ending-pending") << "history\n";
    fs::remove(db);
    EXPECT_EQ(run({"verify", sealed_h, "--seal-key", key}, sealed_h + "-verify"), 0) << slurp(sealed_h + "-verify.stdout");
    const std::string passport = slurp(sealed_h + "/passport.json");
    ASSERT_EQ(run({"run", "--resume", sealed_h, "--yes", "--seal-key", key}, sealed_h + "-resume"), 0)
        << slurp(sealed_h + "-resume.stderr");
    EXPECT_NE(slurp(sealed_h + "-resume.stderr").find("its ending is finished: the history row recorded"),
              std::string::npos)
        << slurp(sealed_h + "-resume.stderr");
    EXPECT_EQ(slurp(sealed_h + "/passport.json"), passport);
    EXPECT_FALSE(fs::exists(sealed_h + "/.ending-pending"));
    EXPECT_EQ(run({"verify", sealed_h, "--seal-key", key}, sealed_h + "-verify2"), 0);
    EXPECT_EQ(run({"history", "--db", db, "--csv"}, sealed_h + "-list"), 0);
    EXPECT_NE(slurp(sealed_h + "-list.stdout").find(",PASS,"), std::string::npos) << slurp(sealed_h + "-list.stdout");
    std::ofstream(sealed_h + "/.ending-pending") << "history\n";
    std::string edited = passport;
    edited.replace(edited.find("\"outcome\": \"PASS\""), 17, "\"outcome\": \"FAIL\"");
    std::ofstream(sealed_h + "/passport.json") << edited;
    EXPECT_EQ(run({"run", "--resume", sealed_h, "--yes", "--seal-key", key}, sealed_h + "-edited"), 2);
    EXPECT_NE(slurp(sealed_h + "-edited.stderr").find("the run is complete: its seal states the outcome PASS"),
              std::string::npos)
        << slurp(sealed_h + "-edited.stderr");
  }

  // A key others may read is refused before anything is written.
  const std::string loose = write_key(d + "/loose.key", 'l', 0644);
  EXPECT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", d + "/loose", "--seal-key", loose},
                d + "/loose-io"),
            2);
  EXPECT_NE(slurp(d + "/loose-io.stderr").find(loose + ": station key may be read or written by others (mode 0644)"),
            std::string::npos)
      << slurp(d + "/loose-io.stderr");
  EXPECT_FALSE(fs::exists(d + "/loose"));

  {
    // Stopped mid-recording (ABORTED): the capture it was writing is its own record, sealed as
    // written by the final seal, so the folder verifies and the history takes it with the key (a
    // line integrator's review: "captures/in-run-U10.cap: not sealed (added after the seal)",
    // verify 1, `history --record` exit 2). Its resume sets that capture aside and verifies too.
    const std::string ab = d + "/aborted", db = d + "/aborted.sqlite";
    ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", ab, "--inject", "sigint@150", "--seal-key",
                   key},
                  ab + "-io"),
              3)
        << slurp(ab + "-io.stderr");
    const json sealed = read_json(ab + "/seal.json");
    EXPECT_EQ(sealed["outcome"], "ABORTED");
    const json passport = read_json(ab + "/passport.json");
    std::string partial;
    for (const auto& [rel, mac] : sealed["files"].items())
      if (rel.rfind("captures/", 0) == 0 &&
          std::find(passport["captures"].begin(), passport["captures"].end(), rel) == passport["captures"].end())
        partial = rel;
    ASSERT_FALSE(partial.empty()) << "sigint@150 stops a recording: " << sealed.dump(1);
    EXPECT_EQ(run({"verify", ab, "--seal-key", key}, ab + "-verify"), 0) << slurp(ab + "-verify.stdout");
    EXPECT_NE(slurp(ab + "-verify.stdout").find("ok       " + partial), std::string::npos) << slurp(ab + "-verify.stdout");
    // ... and says the run may go on, with the command that tells how (a technician's review: it
    // said "verified ... outcome ABORTED" and no more).
    EXPECT_NE(slurp(ab + "-verify.stdout")
                  .find("note: the run stopped before its verdict (outcome ABORTED): `rig run --dry-run --resume " + ab +
                        " --seal-key " + key + "` says whether and how it goes on\n"),
              std::string::npos)
        << slurp(ab + "-verify.stdout");
    EXPECT_EQ(run({"history", "--db", "sqlite:" + db, "--record", ab, "--seal-key", key}, ab + "-record"), 0)
        << slurp(ab + "-record.stderr");
    ASSERT_EQ(run({"run", "--resume", ab, "--yes", "--no-history", "--seal-key", key}, ab + "-resume"), 0)
        << slurp(ab + "-resume.stderr");
    EXPECT_TRUE(fs::exists(ab + "/" + partial + ".interrupted-1"));
    EXPECT_EQ(run({"verify", ab, "--seal-key", key}, ab + "-reverify"), 0) << slurp(ab + "-reverify.stdout");
    // The set-aside record is outside the seal: named, not judged (it was not mentioned).
    EXPECT_NE(slurp(ab + "-reverify.stdout").find("note: not covered by the seal (set-aside records, temporary or hidden "
                                                  "files; the verdict does not rest on them): " + partial + ".interrupted-1"),
              std::string::npos)
        << slurp(ab + "-reverify.stdout");
    // An empty folder added after the seal holds no record: named there too (it went unmentioned).
    fs::create_directories(ab + "/added-empty");
    EXPECT_EQ(run({"verify", ab, "--seal-key", key}, ab + "-reverify2"), 0) << slurp(ab + "-reverify2.stdout");
    EXPECT_NE(slurp(ab + "-reverify2.stdout").find("added-empty/ (empty)"), std::string::npos)
        << slurp(ab + "-reverify2.stdout");
    fs::remove(ab + "/added-empty");
    // Ended ERROR by a capture whose retry lost samples too: that last record is kept as written
    // and sealed with it.
    const std::string gap = d + "/gap";
    ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", gap, "--inject", "drop@29000:10",
                   "--inject", "drop@32000:10", "--seal-key", key},
                  gap + "-io"),
              4)
        << slurp(gap + "-io.stderr");
    EXPECT_EQ(read_json(gap + "/seal.json")["outcome"], "ERROR");
    EXPECT_EQ(read_json(gap + "/seal.json")["files"].count("captures/run03-U10.cap"), 1u);
    EXPECT_EQ(run({"verify", gap, "--seal-key", key}, gap + "-verify"), 0) << slurp(gap + "-verify.stdout");
  }

  // Interrupted, sealed: kept aside, then copies of it edited.
  const std::string base = d + "/base";
  ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", base, "--inject", "sigkill@180", "--seal-key",
                 key},
                d + "/base-io"),
            128 + SIGKILL);
  int k = 0;
  auto copy = [&] {
    const std::string f = d + "/f" + std::to_string(++k);
    fs::copy(base, f, fs::copy_options::recursive);
    return f;
  };
  auto refused = [&](const std::string& f, const std::vector<std::string>& extra, const std::string& says) {
    std::vector<std::string> args = {"run", "--resume", f, "--yes", "--no-history"};
    args.insert(args.end(), extra.begin(), extra.end());
    std::vector<std::string> dry = {"run", "--resume", f, "--dry-run"};
    dry.insert(dry.end(), extra.begin(), extra.end());
    EXPECT_EQ(run(dry, f + "-dry"), 2) << says;
    EXPECT_NE(slurp(f + "-dry.stderr").find(says), std::string::npos) << slurp(f + "-dry.stderr");
    EXPECT_EQ(run(args, f + "-io"), 2) << says;
    EXPECT_NE(slurp(f + "-io.stderr").find(says), std::string::npos) << slurp(f + "-io.stderr");
    EXPECT_FALSE(fs::exists(f + "/passport.json")) << says;
  };
  refused(copy(), {}, "is sealed (seal.json): resume it with the station's key");
  {
    // Stopped between two seals, only the previous one there: the refusal names it (it named seal.json).
    const std::string f = copy();
    fs::copy_file(f + "/seal.json", f + "/seal.prev.json", fs::copy_options::overwrite_existing);
    fs::remove(f + "/seal.json");
    refused(f, {}, "is sealed (seal.prev.json): resume it with the station's key");
  }
  {
    // An unsealed folder is not sealed by a resume with a key.
    const std::string f = copy();
    fs::remove(f + "/seal.json");
    fs::remove(f + "/seal.prev.json");
    refused(f, {"--seal-key", key}, "is not sealed (no seal.json): the key cannot vouch for files it never sealed");
  }
  refused(copy(), {"--seal-key", other}, "sealed with another key");
  {
    // F7 edited profile.toml's limits and copied its digest into the checkpoint; with a seal any
    // edit of it is refused, even one the digest does not see (a comment).
    const std::string f = copy();
    std::string prof = slurp(f + "/profile.toml");
    prof += "\n# loosened\n";
    std::ofstream(f + "/profile.toml") << prof;
    refused(f, {"--seal-key", key}, "profile.toml: changed since it was sealed");
  }
  {
    // A capture rewritten: named.
    const std::string f = copy();
    std::ofstream(f + "/captures/run01-U10.cap", std::ios::app) << "x";
    refused(f, {"--seal-key", key}, "captures/run01-U10.cap: changed since it was sealed");
  }
  {
    // The seal's list edited (an entry dropped) no longer holds as a whole.
    const std::string f = copy();
    json s = json::parse(slurp(f + "/seal.json"));
    s["files"].erase("profile.toml");
    std::ofstream(f + "/seal.json") << s.dump(1);
    refused(f, {"--seal-key", key}, "its list of files or its outcome was edited");
  }
  {
    // A file put in the folder is never sealed: a seal lists only what the run wrote. The resume
    // goes on (it reads only what the seal vouches for); verify names the file.
    const std::string f = copy();
    std::ofstream(f + "/qa-approval.txt") << "approved";
    std::ofstream(f + "/captures/loop-forged.cap") << "x";
    ASSERT_EQ(run({"run", "--resume", f, "--yes", "--no-history", "--seal-key", key}, f + "-io"), 0)
        << slurp(f + "-io.stderr");
    const json s = read_json(f + "/seal.json");
    EXPECT_EQ(s["outcome"], "PASS");
    EXPECT_EQ(s["files"].count("qa-approval.txt"), 0u);
    EXPECT_EQ(s["files"].count("captures/loop-forged.cap"), 0u);
    EXPECT_EQ(run({"verify", f, "--seal-key", key}, f + "-verify"), 1);
    EXPECT_NE(slurp(f + "-verify.stdout").find("qa-approval.txt: not sealed (added after the seal)"), std::string::npos)
        << slurp(f + "-verify.stdout");
    EXPECT_NE(slurp(f + "-verify.stdout").find("captures/loop-forged.cap: not sealed"), std::string::npos);
    // The sealed verdict stands, whatever passport.json says: no resume of a sealed PASS.
    fs::remove(f + "/passport.json");
    EXPECT_EQ(run({"run", "--resume", f, "--yes", "--no-history", "--seal-key", key}, f + "-again"), 2);
    EXPECT_NE(slurp(f + "-again.stderr").find("the run is complete: its seal states the outcome PASS"),
              std::string::npos)
        << slurp(f + "-again.stderr");
  }
  {
    // The captures moved out behind a symbolic link, which the seal would not see.
    const std::string f = copy();
    fs::rename(f + "/captures", f + "-caps");
    fs::create_directory_symlink(f + "-caps", f + "/captures");
    refused(f, {"--seal-key", key}, "/captures: a symbolic link in a sealed run folder");
  }
  {
    // A FIFO in place of a sealed capture: named, not waited on.
    const std::string f = copy();
    fs::remove(f + "/captures/run02-U20.cap");
    ASSERT_EQ(::mkfifo((f + "/captures/run02-U20.cap").c_str(), 0600), 0);
    refused(f, {"--seal-key", key}, "captures/run02-U20.cap: sealed as a file, now not a regular file");
  }
  {
    // A forged passport put in the folder before a sealed run: the run is refused before it
    // writes anything (the folder holds what reads as a finished run), so no seal can ever sit
    // beside the forgery. (Before, the run went on and only its seal left the forgery out.)
    const std::string f = d + "/forged";
    fs::create_directories(f);
    std::ofstream(f + "/passport.json") << "{\"outcome\": \"PASS\"}";
    ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", f, "--seal-key", key}, f + "-io"), 2)
        << slurp(f + "-io.stderr");
    EXPECT_NE(slurp(f + "-io.stderr").find(f + " holds a finished run (its passport says PASS)"), std::string::npos)
        << slurp(f + "-io.stderr");
    EXPECT_FALSE(fs::exists(f + "/seal.json"));
    EXPECT_EQ(slurp(f + "/passport.json"), "{\"outcome\": \"PASS\"}");
  }
  {
    // A FIFO where the rig writes a temporary file (it once stalled the run, so the stop fell
    // between seals): the FIFO was replaced and the run's folder did not verify. Since
    // 2026-12-07 a sealed run's --out that holds anything is refused first (exit 2, the FIFO as
    // it was, nothing written): a sealed PASS beside a file it did not write never verified.
    const std::string f = d + "/fifo-tmp";
    fs::create_directories(f);
    ASSERT_EQ(::mkfifo((f + "/checkpoint.json.tmp").c_str(), 0600), 0);
    ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", f, "--inject", "sigkill@150",
                   "--seal-key", key},
                  f + "-io"),
              2)
        << slurp(f + "-io.stderr");
    EXPECT_NE(slurp(f + "-io.stderr").find(f + " holds checkpoint.json.tmp, which the run does not write"),
              std::string::npos)
        << slurp(f + "-io.stderr");
    EXPECT_TRUE(fs::is_fifo(f + "/checkpoint.json.tmp"));
    EXPECT_FALSE(fs::exists(f + "/run.json"));
  }
  {
    // FIFOs where the rig writes the report's temporary file and the profile (the third review:
    // the run stalled after its passport, before its seal, with no signal ending it): the
    // temporary file is replaced, the profile refused.
    const std::string f = d + "/fifos";
    fs::create_directories(f);
    ASSERT_EQ(::mkfifo((f + "/report.html.tmp").c_str(), 0600), 0);
    ASSERT_EQ(::mkfifo((f + "/profile.toml").c_str(), 0600), 0);
    // A profile.toml the run did not write is not replaced (nor opened): exit 2 before the run.
    ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", f, "--seal-key", key}, f + "-io0"), 2);
    EXPECT_NE(slurp(f + "-io0.stderr").find("holds profile.toml, which a run writes, but no run"), std::string::npos)
        << slurp(f + "-io0.stderr");
    fs::remove(f + "/profile.toml");
    // A sealed run refuses the folder that holds a file it did not write (since 2026-12-07); an
    // unsealed run replaces the FIFO and does not stall.
    ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", f, "--seal-key", key}, f + "-io1"), 2)
        << slurp(f + "-io1.stderr");
    EXPECT_NE(slurp(f + "-io1.stderr").find("holds report.html.tmp, which the run does not write"), std::string::npos)
        << slurp(f + "-io1.stderr");
    ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", f}, f + "-io"), 0) << slurp(f + "-io.stderr");
    EXPECT_TRUE(fs::is_regular_file(f + "/report.html"));
    EXPECT_FALSE(fs::exists(f + "/report.html.tmp"));
    const std::string g = d + "/sealed-then-edited";
    ASSERT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", g, "--seal-key", key}, g + "-io"), 0)
        << slurp(g + "-io.stderr");
    EXPECT_EQ(run({"verify", g, "--seal-key", key}, g + "-verify"), 0) << slurp(g + "-verify.stdout");
    // A passport whose outcome is not the sealed one does not verify, even before its MAC is read.
    std::string p = slurp(g + "/passport.json");
    p.replace(p.find("\"outcome\": \"PASS\""), 17, "\"outcome\": \"FAIL\"");
    std::ofstream(g + "/passport.json") << p;
    EXPECT_EQ(run({"verify", g, "--seal-key", key}, g + "-edited"), 1);
  }
  // An empty key is not "no key".
  EXPECT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", d + "/empty", "--seal-key", ""},
                d + "/empty-io"),
            2);
  EXPECT_NE(slurp(d + "/empty-io.stderr").find("--seal-key: empty value"), std::string::npos)  // every text option's rule
      << slurp(d + "/empty-io.stderr");
  ::setenv("RIG_SEAL_KEY", "", 1);  // inherited by the child
  EXPECT_EQ(run({"run", "--profile", "ci", "--yes", "--no-history", "--out", d + "/empty-env"}, d + "/empty-env-io"), 2);
  ::unsetenv("RIG_SEAL_KEY");
  EXPECT_NE(slurp(d + "/empty-env-io.stderr").find("--seal-key / RIG_SEAL_KEY: empty"), std::string::npos);
  EXPECT_FALSE(fs::exists(d + "/empty-env"));
  {
    // Stopped after the new seal was written, before the checkpoint it covers: seal.json holds
    // for a checkpoint that never came, seal.prev.json for the one there. Resumed with the key,
    // the run ends as the uninterrupted one and verifies.
    const std::string f = copy();
    fs::rename(f + "/seal.json", f + "/seal.prev.json");
    json s = json::parse(slurp(f + "/seal.prev.json"));
    s["files"]["checkpoint.json"] = std::string(64, '0');  // not this key's MAC of anything here
    std::ofstream(f + "/seal.json") << s.dump(1);
    ASSERT_EQ(run({"run", "--resume", f, "--yes", "--no-history", "--seal-key", key}, f + "-io"), 0)
        << slurp(f + "-io.stderr");
    EXPECT_EQ(without_session_fields(read_json(f + "/passport.json")), without_session_fields(ref.passport));
    EXPECT_EQ(run({"verify", f, "--seal-key", key}, f + "-verify"), 0) << slurp(f + "-verify.stdout");
    EXPECT_FALSE(fs::exists(f + "/seal.prev.json"));
    // The partial capture the stop left is kept aside, unsealed (its content was never checked).
    EXPECT_TRUE(fs::exists(f + "/captures/raw-U10.cap.interrupted-1"));
    EXPECT_EQ(read_json(f + "/seal.json")["files"].count("captures/raw-U10.cap.interrupted-1"), 0u);
    // A sealed file replaced by a folder: not verified, named.
    fs::remove(f + "/junit.xml");
    fs::create_directory(f + "/junit.xml");
    EXPECT_EQ(run({"verify", f, "--seal-key", key}, f + "-dir"), 1);
    EXPECT_NE(slurp(f + "-dir.stdout").find("NOT-FILE junit.xml"), std::string::npos) << slurp(f + "-dir.stdout");
  }
  {
    // What every ending writes again (the passport, junit.xml, ...) is not needed by a resume: a
    // stray one does not stop it, and the resume writes its own.
    const std::string f = copy();
    std::ofstream(f + "/passport.json") << "{\"outcome\": \"PASS\"}";
    ASSERT_EQ(run({"run", "--resume", f, "--yes", "--no-history", "--seal-key", key}, f + "-io"), 0)
        << slurp(f + "-io.stderr");
    EXPECT_EQ(without_session_fields(read_json(f + "/passport.json")), without_session_fields(ref.passport));
  }
}

// report.html that cannot be written at the ending (a full disk; here its temporary name held
// by a folder the rig cannot remove) is a step left for the resume, as the history row is: the
// run's verdict stands (exit 0), an earlier page goes (it would contradict the passport), the
// folder lists the step, the resume writes the page. With a seal the final seal is made without
// the page and the resume seals again with it, no device opened (a review: the run ended PASS
// without the page, its resume said "nothing to resume", and the seal made without the page
// failed `rig verify` for good once `rig report` drew it).
TEST(Campaign, AReportTheEndingCouldNotWriteIsWrittenByTheResume) {
  const std::string d = tmp("campaign-report-left");
  fs::create_directories(d);
  const std::string key = write_key(d + "/station.key", 'k');
  for (const bool sealed : {false, true}) {
    const std::string r = d + (sealed ? "/sealed" : "/plain");
    // An earlier ending's page, which must not stand beside this passport: the run stopped by a
    // signal (ABORTED, its page written), then resumed to its end.
    std::vector<std::string> first = {"run", "--profile", "ci", "--yes", "--no-history", "--out", r, "--inject", "sigint@150"};
    if (sealed) first.insert(first.end(), {"--seal-key", key});
    ASSERT_EQ(run(first, r + "-first"), 3) << slurp(r + "-first.stderr");
    ASSERT_TRUE(fs::is_regular_file(r + "/report.html"));
    fs::create_directories(r + "/report.html.tmp/held");
    std::vector<std::string> args = {"run", "--resume", r, "--yes", "--no-history"};
    if (sealed) args.insert(args.end(), {"--seal-key", key});
    ASSERT_EQ(run(args, r + "-io"), 0) << slurp(r + "-io.stderr");
    auto bring_ups = [&] {
      const std::string log = slurp(r + "/run.log");
      std::size_t n = 0;
      for (std::size_t at = log.find("bring-up"); at != std::string::npos; at = log.find("bring-up", at + 1)) ++n;
      return n;
    };
    const std::size_t before = bring_ups();
    EXPECT_EQ(read_json(r + "/passport.json")["outcome"], "PASS");
    EXPECT_FALSE(fs::exists(r + "/report.html")) << "the earlier page went";
    const std::string err = slurp(r + "-io.stderr");
    EXPECT_NE(err.find("report.html not written: "), std::string::npos) << err;
    EXPECT_NE(err.find("(rig run --resume " + r + (sealed ? " --seal-key " + key + " writes it and seals it)" : std::string(" writes it)"))),
              std::string::npos)
        << err;
    EXPECT_NE(slurp(r + "/.ending-pending").find("report\n"), std::string::npos);
    if (sealed) {  // sealed without the page: what is there verifies, and the unfinished ending is said
      EXPECT_EQ(run({"verify", r, "--seal-key", key}, r + "-early"), 0) << slurp(r + "-early.stdout");
      EXPECT_NE(slurp(r + "-early.stdout").find("note: the run's ending is not finished (.ending-pending: report)"),
                std::string::npos)
          << slurp(r + "-early.stdout");
    }
    fs::remove_all(r + "/report.html.tmp");
    std::vector<std::string> resume = {"run", "--resume", r, "--yes", "--no-history"};
    if (sealed) resume.insert(resume.end(), {"--seal-key", key});
    std::vector<std::string> dry = resume;
    dry.emplace_back("--dry-run");
    ASSERT_EQ(run(dry, r + "-dry"), 0) << slurp(r + "-dry.stderr");
    EXPECT_NE(slurp(r + "-dry.stdout").find(sealed ? "a resume does what is left (report.html written and sealed with the rest)"
                                                   : "a resume does what is left (report.html written)"),
              std::string::npos)
        << slurp(r + "-dry.stdout");
    ASSERT_EQ(run(resume, r + "-resume"), 0) << slurp(r + "-resume.stderr");
    ASSERT_GT(before, 0u);
    EXPECT_EQ(bring_ups(), before) << "the resume finished the ending without the devices";
    EXPECT_TRUE(fs::is_regular_file(r + "/report.html"));
    EXPECT_NE(slurp(r + "/report.html").find("PASS"), std::string::npos) << "the run's own page";
    EXPECT_FALSE(fs::exists(r + "/.ending-pending"));
    EXPECT_EQ(read_json(r + "/passport.json")["outcome"], "PASS");
    if (sealed) {
      EXPECT_EQ(run({"verify", r, "--seal-key", key}, r + "-verify"), 0) << slurp(r + "-verify.stdout");
      EXPECT_NE(slurp(r + "-verify.stdout").find("ok       report.html"), std::string::npos)
          << slurp(r + "-verify.stdout");
    }
  }
}
