// Profiles: the built-ins load; malformed files are rejected with file and line.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

#include <gtest/gtest.h>

#include "procedures/acceptance/profile.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"

namespace fs = std::filesystem;
using rig::ConfigError;
using rig::acceptance::load_profile;
using rig::acceptance::load_profile_table;
using rig::acceptance::parse_profile;
using rig::acceptance::unjudged_blocks_note;

namespace {
std::string write_tmp(const std::string& name, const std::string& text) {
  const std::string d = fs::temp_directory_path() / ("rigprof-" + std::to_string(::getpid()));
  fs::create_directories(d);
  const std::string p = d + "/" + name;
  std::ofstream(p) << text;
  return p;
}
std::string error_of(const std::string& path) {
  try {
    load_profile(path);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Profile, BuiltinPaperMatchesTheMethod) {
  const auto p = load_profile("paper");
  EXPECT_EQ(p.name, "paper");
  EXPECT_EQ(p.order.size(), 12u);
  EXPECT_EQ(p.run_s, 100.0);
  EXPECT_EQ(p.in_run_s, 1800.0);
  EXPECT_EQ(p.raw_s, 3600.0);
  EXPECT_EQ(p.rate_hz, 1000.0);
  ASSERT_EQ(p.in_run_blocks_s.size(), 2u);
  EXPECT_EQ(p.in_run_blocks_s[1], 200.0);
  ASSERT_EQ(p.filter.sections.size(), 1u);
  EXPECT_NEAR(p.filter.sections[0].b0, 0.148895, 1e-12);
  EXPECT_EQ(p.classes.size(), 3u);
  EXPECT_TRUE(p.limits.count("bias"));
}

TEST(Profile, CiHasTheSamePhasesInSeconds) {
  const auto ci = load_profile("ci");
  const auto paper = load_profile("paper");
  EXPECT_EQ(ci.order, paper.order);
  EXPECT_LT(ci.planned_total_s(), 300.0);
}

TEST(Profile, SyntaxErrorNamesFileAndLine) {
  const std::string p = write_tmp("syntax.toml", "[profile]\nname = \"x\"\n[procedure\nrun_s = 1\n");
  const std::string e = error_of(p);
  EXPECT_NE(e.find(p + ":3:"), std::string::npos) << e;
}

TEST(Profile, WrongTypeNamesFileLineAndKey) {
  const std::string p = write_tmp("type.toml",
                                  "[profile]\nname = \"x\"\n[procedure]\norder = [\"U10\", \"U20\"]\n"
                                  "run_s = \"long\"\nin_run_s = 10\nraw_s = 10\n");
  const std::string e = error_of(p);
  EXPECT_NE(e.find(p + ":5:"), std::string::npos) << e;
  EXPECT_NE(e.find("run_s"), std::string::npos) << e;
}

// A name of blanks reads as none on the passport and in the history (a review: " " was taken).
TEST(Profile, ANameOfBlanksOrWithABlankAtAnEndIsRefused) {
  for (const char* name : {" ", "   ", " line-2", "line-2 "}) {
    const std::string p = write_tmp("blank.toml", std::string("[profile]\nname = \"") + name + "\"\n");
    const std::string e = error_of(p);
    EXPECT_NE(e.find(p + ":2:"), std::string::npos) << e;
    EXPECT_NE(e.find("the profile's name cannot begin or end with a blank"), std::string::npos) << e;
  }
}

TEST(Profile, UnknownKeyIsRejected) {
  const std::string p = write_tmp("typo.toml",
                                  "[profile]\nname = \"x\"\n[procedure]\norder = [\"U10\", \"U20\"]\n"
                                  "run_s = 1\nin_run_s = 10\nraw_s = 10\nrun_sec = 5\n");
  const std::string e = error_of(p);
  EXPECT_NE(e.find(p + ":8:"), std::string::npos) << e;
  EXPECT_NE(e.find("run_sec"), std::string::npos) << e;
}

TEST(Profile, UnpairedOrderIsRejected) {
  const std::string p = write_tmp("order.toml",
                                  "[profile]\nname = \"x\"\n[procedure]\norder = [\"U10\", \"U10\", \"U20\"]\n"
                                  "run_s = 1\nin_run_s = 10\nraw_s = 10\n");
  EXPECT_NE(error_of(p).find("as many U10 runs as U20"), std::string::npos);
}

TEST(Profile, BadLimitsAndClassesAreRejected) {
  const std::string base =
      "[profile]\nname = \"x\"\n[procedure]\norder = [\"U10\", \"U20\"]\nrun_s = 1\nin_run_s = 10\nraw_s = 10\n"
      "in_run_blocks_s = [1.0, 2.0]\n";
  EXPECT_NE(error_of(write_tmp("lim.toml", base + "[limits]\nbias = [1.0, -1.0]\n")).find("min <= max"),
            std::string::npos);
  // The error names file:line:column and the value as written (README: every bad-input error).
  const std::string swapped = write_tmp("lim3.toml", base + "[limits]\nbias = [1e-3, -1e-3]\n");
  EXPECT_EQ(error_of(swapped), swapped + ":10:8: 'bias' = [ 0.001, -0.001 ]: limits must be [min, max] with min <= max");
  // Each element as its shortest text (toml++ wrote [ 0.29999999999999999, 0.10000000000000001 ]).
  const std::string tenths = write_tmp("lim5.toml", base + "[limits]\nbias = [0.3, 0.1]\n");
  EXPECT_EQ(error_of(tenths), tenths + ":10:8: 'bias' = [ 0.3, 0.1 ]: limits must be [min, max] with min <= max");
  // The value's and the bound's digits where they differ (it read '= 0.002 is out of range [0.002, ...').
  std::string near = base;
  near.replace(near.find("run_s = 1\n"), 10, "run_s = 0.00199999999\n");
  const std::string short_run = write_tmp("lim6.toml", near);
  EXPECT_EQ(error_of(short_run), short_run + ":5:9: 'run_s' = 0.00199999999 is out of range [0.002, 1000000]");
  // A limit nearer 0 than a double holds: toml++ reads it as 0; refused at its place, as written
  // (it became [0, 0], failing every DUT without a word: a review). 0.0, -0.0 and 0e5 are zero.
  const std::string tiny = write_tmp("lim7.toml", base + "[limits]\nbias = [0.0, 1e-400]\n");
  EXPECT_EQ(error_of(tiny), tiny + ":10:14: 1e-400 is nearer 0 than the smallest double (about 4.9e-324): write 0, or a "
                                   "value a double holds");
  const std::string spaced = write_tmp("lim8.toml", base + "[limits]\nbias = [ -0.0, 2.5E-999 ] # g\n");
  EXPECT_NE(error_of(spaced).find(":10:16: 2.5E-999 is nearer 0"), std::string::npos) << error_of(spaced);
  // Columns are code points: UTF-8 before the value on its line (a key "µµ", 4 bytes in 2).
  const std::string utf8 = write_tmp("lim10.toml", base + "[limits]\n\"\xc2\xb5\xc2\xb5\" = 1e-400\n");
  EXPECT_NE(error_of(utf8).find(":10:8: 1e-400 is nearer 0"), std::string::npos) << error_of(utf8);
  EXPECT_EQ(error_of(write_tmp("lim9.toml", base + "[limits]\nbias = [-0.0, 0e5]\n")).find("nearer 0"), std::string::npos);
  const std::string three = write_tmp("lim4.toml", base + "[limits]\nbias = [0, 1, 2]\n");
  EXPECT_EQ(error_of(three), three + ":10:8: 'bias' = [ 0, 1, 2 ]: limits are two numbers [min, max], got 3");
  EXPECT_NE(error_of(write_tmp("lim2.toml", base + "[limits]\nbais = [0, 1]\n")).find("unknown measurement 'bais' in [limits] (known: bias, base_error, in_run_b_allan,"),
            std::string::npos);
  const std::string cls = write_tmp("cls.toml", base + "[[classes]]\nname = \"a\"\nmax_b_g = 2e-5\n[[classes]]\nname = "
                                                      "\"b\"\nmax_b_g = 1e-5\n");
  EXPECT_EQ(error_of(cls), cls + ":14:11: 'max_b_g' = 1e-05: [[classes]] must be in ascending max_b_g (the class before "
                                 "has 2e-05)");
  // A class the passport cannot name (a review: "precision" twice, and "" accepted).
  const std::string twice = write_tmp("cls2.toml", base + "[[classes]]\nname = \"a\"\nmax_b_g = 1e-5\n[[classes]]\nname = "
                                                          "\"a\"\nmax_b_g = 2e-5\n");
  EXPECT_EQ(error_of(twice), twice + ":13:8: 'name' = 'a': another [[classes]] entry has that name");
  const std::string blank = write_tmp("cls3.toml", base + "[[classes]]\nname = \" \"\nmax_b_g = 1e-5\n");
  EXPECT_EQ(error_of(blank), blank + ":10:8: 'name' = ' ': a class needs a name");
  // A class limited with no class to read could never be measured: every run would FAIL after the
  // whole procedure (a review: the dry run said nothing). With [[classes]], as before.
  const std::string unclassed = write_tmp("cls4.toml", base + "[limits]\naccuracy_class = [1.0, 2.0]\n");
  EXPECT_EQ(error_of(unclassed), unclassed + ":10:18: [limits] accuracy_class is limited, but the profile has no "
                                             "accuracy classes ([[classes]]): it could never be measured and every run "
                                             "would FAIL; give [[classes]] or remove the limit");
  EXPECT_EQ(error_of(write_tmp("cls5.toml", base + "[limits]\naccuracy_class = [1.0, 2.0]\n[[classes]]\nname = "
                                                   "\"a\"\nmax_b_g = 1e-5\n")),
            "");
  const std::string blocks = write_tmp("blk.toml", "[profile]\nname = \"x\"\n[procedure]\norder = [\"U10\", \"U20\"]\n"
                                                   "run_s = 1\nin_run_s = 10\nraw_s = 10\nin_run_blocks_s = [1.0, 6.0]\n");
  EXPECT_EQ(error_of(blocks), blocks + ":8:19: 'in_run_blocks_s' = [ 1.0, 6.0 ]: 6 s: each block length must be > 0 "
                                       "and give at least 2 blocks in in_run_s = 10");
  const std::string based = write_tmp("base.toml", "base = \"cj\"\n");
  EXPECT_EQ(error_of(based), based + ":1:8: 'base' = 'cj': must name a built-in profile (ci, paper)");
}

// `NAME = []` in [limits] removes the base's limit: that value reported, not judged (a file could
// loosen an inherited limit but not remove one: an integrator's review).
TEST(Profile, AnEmptyLimitRemovesTheBasesLimit) {
  const auto p = load_profile(write_tmp("unlimit.toml", "base = \"ci\"\n[profile]\nname = \"ci-unlimited\"\n[limits]\n"
                                                        "bandwidth_0p5 = []\nsettling_time = []\n"));
  EXPECT_EQ(p.limits.count("bandwidth_0p5"), 0u);
  EXPECT_EQ(p.limits.count("settling_time"), 0u);
  EXPECT_EQ(p.limits.count("bias"), 1u) << "the others stay the base's";
  EXPECT_EQ(load_profile("ci").limits.count("bandwidth_0p5"), 1u);
  // Said before the run, as a dropped block's limits are (a review: no Note, the value UNSET and
  // the run PASS); the built-ins judge every value named here.
  EXPECT_EQ(unjudged_blocks_note(p, {}),
            p.source + ": bandwidth_0p5, settling_time have no limits: UNSET in the passport, never FAIL (give them "
                       "in [limits] to judge them)");
  EXPECT_EQ(unjudged_blocks_note(load_profile("paper"), {}), "");
}

TEST(Profile, FileCanStartFromABuiltinAndOverride) {
  const std::string p = write_tmp("short.toml", "base = \"ci\"\n[profile]\nname = \"shorter\"\n[procedure]\nraw_s = 20.0\n");
  const auto prof = load_profile(p);
  EXPECT_EQ(prof.name, "shorter");
  EXPECT_EQ(prof.raw_s, 20.0);
  EXPECT_EQ(prof.run_s, load_profile("ci").run_s);
}

// A file that changes the GOST blocks of its base (helper review): the base's limits for blocks
// the file no longer has were refused as "unknown measurement", so a custom block length needed
// a copy of the whole profile. They are dropped; a limit for a length the file keeps stays.
TEST(Profile, AFileThatChangesTheGostBlocksKeepsTheBasesLimitsOnlyForBlocksItHas) {
  const auto ci = load_profile("ci");
  ASSERT_TRUE(ci.limits.count("in_run_b_gost_2s"));
  const auto five = load_profile(write_tmp("b5.toml", "base = \"ci\"\n[procedure]\nin_run_blocks_s = [5.0]\n"));
  EXPECT_EQ(five.in_run_blocks_s, std::vector<double>{5.0});
  for (const auto& [name, lim] : five.limits) EXPECT_EQ(name.rfind("in_run_b_gost_", 0), std::string::npos) << name;
  const auto two = load_profile(write_tmp("b25.toml", "base = \"ci\"\n[procedure]\nin_run_blocks_s = [2.0, 5.0]\n"
                                                      "[limits]\nin_run_b_gost_5s = [0.0, 2.0e-4]\n"));
  EXPECT_EQ(two.limits.at("in_run_b_gost_2s"), ci.limits.at("in_run_b_gost_2s"));
  EXPECT_EQ(two.limits.at("in_run_b_gost_5s"), (std::pair<double, double>{0.0, 2.0e-4}));
  EXPECT_FALSE(two.limits.count("in_run_b_gost_4s"));
  // A file's own limit for a block it does not have is still its mistake, named.
  const std::string own = write_tmp("b7.toml", "base = \"ci\"\n[procedure]\nin_run_blocks_s = [5.0]\n"
                                               "[limits]\nin_run_b_gost_7s = [0.0, 1.0]\n");
  EXPECT_NE(error_of(own).find("in_run_b_gost_7s"), std::string::npos) << error_of(own);
  // What is left unjudged is said (a run prints it: those values are UNSET, never FAIL; it
  // passed without a word, an automation review); every block with limits leaves nothing to say.
  std::string source;
  std::vector<std::string> dropped;
  const std::string b5 = write_tmp("b5.toml", "base = \"ci\"\n[procedure]\nin_run_blocks_s = [5.0]\n");
  const auto t5 = load_profile_table(b5, source, &dropped);
  EXPECT_EQ(dropped, (std::vector<std::string>{"in_run_b_gost_2s", "in_run_b_gost_4s"}));
  EXPECT_EQ(unjudged_blocks_note(parse_profile(t5, source), dropped),
            b5 + ": its own in_run_blocks_s leaves out its base's limits (in_run_b_gost_2s, in_run_b_gost_4s); "
                 "in_run_b_gost_5s has no limits: UNSET in the passport, never FAIL (give them in [limits] to judge "
                 "them)");
  const std::string b25 = write_tmp("b25.toml", "base = \"ci\"\n[procedure]\nin_run_blocks_s = [2.0, 5.0]\n"
                                                "[limits]\nin_run_b_gost_5s = [0.0, 2.0e-4]\n");
  const auto t25 = load_profile_table(b25, source, &dropped);
  EXPECT_EQ(dropped, std::vector<std::string>{"in_run_b_gost_4s"});
  EXPECT_EQ(unjudged_blocks_note(parse_profile(t25, source), dropped), "");
  EXPECT_EQ(unjudged_blocks_note(ci, {}), "") << "every block limited";
  // A block added beside the base's, nothing dropped: said too (a code review).
  const std::string b245 = write_tmp("b245.toml", "base = \"ci\"\n[procedure]\nin_run_blocks_s = [2.0, 4.0, 5.0]\n");
  const auto t245 = load_profile_table(b245, source, &dropped);
  EXPECT_TRUE(dropped.empty());
  EXPECT_EQ(unjudged_blocks_note(parse_profile(t245, source), dropped),
            b245 + ": in_run_b_gost_5s has no limits: UNSET in the passport, never FAIL (give them in [limits] to judge "
                   "them)");
}

// A value the file inherits is named where it came from: the built-in base's line, not
// "command-line option" (toml++ drops a copied node's position; the base's nodes are moved).
TEST(Profile, AnInheritedValueIsNamedByTheBasesLine) {
  const std::string p = write_tmp("short-in-run.toml", "base = \"ci\"\n[procedure]\nin_run_s = 3.0\n");
  EXPECT_EQ(error_of(p), "builtin:ci:15:19: 'in_run_blocks_s' = [ 2.0, 4.0 ]: 2 s: each block length must be > 0 "
                         "and give at least 2 blocks in in_run_s = 3 (inherited by " + p +
                         " from its base; set the key there to change it)");
  // As rig run and rig plant serve read it, the table apart from its parse (they said only the
  // base's line: a technician's review).
  std::string source;
  const toml::table t = rig::acceptance::load_profile_table(p, source);
  try {
    rig::acceptance::parse_profile(t, source);
    ADD_FAILURE() << "parsed";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), error_of(p));
  }
}

// The raw capture holds one segment of its PSD at least: 0.25 s at 1 kHz passed every check and
// the analysis refused it after the whole procedure, as a hardware fault (exit 4), on every
// resume alike (a review).
TEST(Profile, ARawCaptureShorterThanOnePsdSegmentIsRefusedAtItsLine) {
  const std::string p = write_tmp("short-raw.toml", "base = \"ci\"\n[procedure]\nraw_s = 0.25\n");
  EXPECT_EQ(error_of(p), p + ":3:9: 'raw_s' = 0.25: the raw capture must hold at least 256 samples at rate_hz = 1000 "
                             "(one segment of its PSD), 0.256 s; this gives 250");
  EXPECT_EQ(load_profile(write_tmp("raw-256.toml", "base = \"ci\"\n[procedure]\nraw_s = 0.256\n")).raw_s, 0.256);
}

TEST(Profile, BAllanSaysWhichBThePassportLimits) {
  EXPECT_EQ(load_profile("paper").b_allan, "paper");
  const auto prof = load_profile(write_tmp("lsq.toml", "base = \"ci\"\n[analysis]\nb_allan = \"lsq\"\n"));
  EXPECT_EQ(prof.b_allan, "lsq");
  const std::string gmwm = write_tmp("gmwm.toml", "base = \"ci\"\n[analysis]\nb_allan = \"gmwm\"\n");
  EXPECT_EQ(error_of(gmwm), gmwm + ":3:11: 'b_allan' = 'gmwm': must be \"paper\" or \"lsq\"");
  EXPECT_NE(error_of(write_tmp("bad.toml", "base = \"ci\"\n[analysis]\nb_allan = \"gmwm\"\n")).find("b_allan"),
            std::string::npos);
}

TEST(Profile, MissingFileSaysWhatExists) {
  const std::string e = error_of("/nonexistent/profile.toml");
  EXPECT_NE(e.find("ci"), std::string::npos);
  EXPECT_NE(e.find("paper"), std::string::npos);
}

// [profile] name names the passport, the history and the default run folder: "" gave a folder
// runs/_-<time>, and an escape sequence in it went to the terminal as it was (a review). Both
// are refused at the name's line; the message shows the control byte as \xNN. A name in
// another script is a name like any other.
TEST(Profile, ANameIsRequiredAndHoldsNoControlCharacter) {
  const std::string empty = write_tmp("empty-name.toml", "base = \"ci\"\n[profile]\nname = \"\"\n");
  EXPECT_NE(error_of(empty).find("empty-name.toml:3:8: 'name' = \"\": the profile's name is required"),
            std::string::npos)
      << error_of(empty);
  const std::string esc = write_tmp("esc-name.toml", "base = \"ci\"\n[profile]\nname = \"x\\u001b[31mRED\"\n");
  const std::string e = error_of(esc);
  EXPECT_NE(e.find("esc-name.toml:3:8: 'name' = \"x\\x1B[31mRED\": a control character"), std::string::npos) << e;
  EXPECT_EQ(e.find('\x1B'), std::string::npos) << e;
  const std::string c1 = write_tmp("csi-name.toml", "base = \"ci\"\n[profile]\nname = \"x\\u009b2J\"\n");
  EXPECT_NE(error_of(c1).find("'name' = \"x\\xC2\\x9B2J\""), std::string::npos) << error_of(c1);
  EXPECT_EQ(load_profile(write_tmp("cyrillic.toml", "base = \"ci\"\n[profile]\nname = \"приёмка\"\n")).name, "приёмка");
}

// A whole number is shown as one, the range's bounds too: `retries = 1000000000` was
// "'retries' = 1e+09" (a review).
TEST(Profile, AWholeNumberOutOfRangeIsShownAsTyped) {
  const std::string p = write_tmp("retries.toml", "base = \"ci\"\n[procedure]\nretries = 1000000000\n");
  EXPECT_NE(error_of(p).find("retries.toml:3:11: 'retries' = 1000000000 is out of range [0, 10]"), std::string::npos)
      << error_of(p);
  // A NaN where no range applies is said to be one (it was "is out of range" with no range).
  const std::string n = write_tmp("nan-limit.toml", "base = \"ci\"\n[limits]\nbias = [0.0, nan]\n");
  EXPECT_NE(error_of(n).find("nan-limit.toml:3:14: 'bias' = nan: not a finite number"), std::string::npos)
      << error_of(n);
}

// A --profile path is shown with its control bytes as \xNN wherever a message names it: the
// file's own errors (FILE:LINE:COL) and a path that is no file.
// A path in a command a message offers is one shell word that reads back to it (the resume hint
// printed `--resume /tmp/we ird\x0Aname`: a review). Checked by a shell.
TEST(ShellWord, APathIsOneWordAShellReadsBackToIt) {
  EXPECT_EQ(rig::shell_word("/data/run-1_a.b"), "/data/run-1_a.b");
  EXPECT_EQ(rig::shell_word("/tmp/we ird"), "'/tmp/we ird'");
  EXPECT_EQ(rig::shell_word("it's"), "'it'\\''s'");
  EXPECT_EQ(rig::shell_word("a\nb'c\\"), "$'a\\x0Ab\\'c\\\\'");
  EXPECT_EQ(rig::shell_word(""), "''");
  EXPECT_EQ(rig::shell_word("/данные/прогон"), "/данные/прогон");
  for (const std::string path : {"/tmp/we ird\nname", "x'y z", "a\\b\tc$d`e", "*?[~#!&;|<>(){}\""}) {
    const std::string got = rig::shell_word(path);
    const std::string file = fs::temp_directory_path() / ("rig-shell-word-" + std::to_string(::getpid()));
    std::ofstream(file) << "printf '%s' " << got << "\n";
    FILE* p = ::popen(("bash " + file).c_str(), "r");
    ASSERT_NE(p, nullptr);
    std::string back;
    for (int c; (c = std::fgetc(p)) != EOF;) back += static_cast<char>(c);
    ::pclose(p);
    fs::remove(file);
    EXPECT_EQ(back, path) << got;
  }
}

TEST(Profile, APathWithControlBytesIsShownEscaped) {
  const std::string dir = fs::temp_directory_path() / ("rigprof-" + std::to_string(::getpid()));
  const std::string p = write_tmp("r\x1B[2J.toml", "base = \"ci\"\n[procedure]\nretries = 11\n");
  const std::string e = error_of(p);
  EXPECT_NE(e.find("r\\x1B[2J.toml:3:11: 'retries' = 11"), std::string::npos) << e;
  EXPECT_EQ(e.find('\x1B'), std::string::npos) << e;
  const std::string missing = error_of(dir + "/none\x07.toml");
  EXPECT_NE(missing.find("none\\x07.toml': no such file"), std::string::npos) << missing;
  EXPECT_EQ(missing.find('\x07'), std::string::npos) << missing;
}
