// The `rig` command line: one subcommand per job (docs/contracts.md).
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "app/abort_cleanup.hpp"
#include "app/commands.hpp"
#include "app/error_words.hpp"
#include "app/output_file.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"
#include "rig/report/db.hpp"

namespace {

// CLI11 reads a number as C's strtod/strtoll do: "" as 0, "0x10" as 16, " 5" with its blank, and
// a whole number in base 0 ("010" as 8, "-1" as 2^64 - 1 for an unsigned option), so `rig table
// move ""` (an empty shell variable) turned the table to 0 degrees and `--unit 010` addressed
// drive 8 (reviews). Every numeric option and argument takes decimal text only: a whole number
// without leading zeros (and without a sign where it is unsigned); "inf" and "nan" pass on to a
// real option's own range check, which names them.
bool decimal_text(const std::string& v, bool whole, bool is_unsigned) {
  // "No sign": '+' neither (`--threads +5` ran, while the message said no sign: a re-test).
  if (is_unsigned && !v.empty() && (v[0] == '-' || v[0] == '+')) return false;
  std::size_t i = (!v.empty() && (v[0] == '+' || v[0] == '-')) ? 1 : 0;
  if (whole && i + 1 < v.size() && v[i] == '0') return false;  // "010": octal to CLI11
  std::string rest = v.substr(i);
  for (char& c : rest) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (!whole && (rest == "inf" || rest == "infinity" || rest == "nan")) return true;
  std::size_t digits = 0;
  while (i < v.size() && std::isdigit(static_cast<unsigned char>(v[i]))) ++i, ++digits;
  if (!whole && i < v.size() && v[i] == '.')
    for (++i; i < v.size() && std::isdigit(static_cast<unsigned char>(v[i])); ++i) ++digits;
  if (digits == 0) return false;
  if (!whole && i < v.size() && (v[i] == 'e' || v[i] == 'E')) {
    ++i;
    if (i < v.size() && (v[i] == '+' || v[i] == '-')) ++i;
    std::size_t exp = 0;
    while (i < v.size() && std::isdigit(static_cast<unsigned char>(v[i]))) ++i, ++exp;
    if (exp == 0) return false;
  }
  return i == v.size();
}

// The unit an option's number is in, as its name or help says it: "ms" (a name ending -ms),
// "fraction" (--confidence, or help saying "fraction"), "%", "Hz", "deg", "s", or "" (g, counts:
// no unit a number is typed with).
std::string option_unit(const CLI::Option& o) {
  const std::string& name = o.get_name();
  const std::string& d = o.get_description();
  const auto says = [&d](const char* w) { return d.find(w) != std::string::npos; };
  if (name.ends_with("-ms")) return "ms";
  if (name.ends_with("confidence") || says("fraction")) return "fraction";
  if (says("%")) return "%";
  if (says("Hz")) return "Hz";
  if (says("degree")) return "deg";
  if (says("second") || says(", s,") || says(", s ")) return "s";
  return "";
}

// Whether a whole number's decimal text (decimal_text checked it) fits the 64 bits CLI11 reads it
// into.
bool fits_64_bits(const std::string& v, bool is_unsigned) {
  const char* b = v.data() + (!v.empty() && v[0] == '+' ? 1 : 0);
  const char* const e = v.data() + v.size();
  std::uint64_t u = 0;
  std::int64_t i = 0;
  return is_unsigned ? std::from_chars(b, e, u).ec == std::errc() : std::from_chars(b, e, i).ec == std::errc();
}

void decimal_numbers_only(CLI::App& app) {
  for (CLI::Option* o : app.get_options()) {
    const std::string shown = o->get_type_name();  // "FLOAT", or with a check's text: "FLOAT:FLOAT in [..]"
    const std::string type = shown.substr(0, shown.find(':'));
    const bool whole = type == "INT" || type == "UINT", real = type == "FLOAT" || type == "NUMBER";
    if (!whole && !real) continue;
    // A whole number whose range starts at 0 or above takes no sign either, whatever its C++ type
    // (`--unit +1` and `--steps +5` ran while `--count +5` was refused: a technician's re-test).
    const auto range = shown.find(" in [");
    const bool is_unsigned =
        type == "UINT" || (whole && range != std::string::npos && range + 5 < shown.size() &&
                           std::isdigit(static_cast<unsigned char>(shown[range + 5])));
    const std::string unit = option_unit(*o);
    // First among the option's checks (transform() puts it in front): the text is a number
    // before a range check reads it, whose own message would then say less.
    o->transform(CLI::Validator(
        [whole, is_unsigned, unit](std::string& v) {
          if (decimal_text(v, whole, is_unsigned)) return std::string();
          // A number with the option's own unit after it (`90°`, `100Hz`, `5s`): said so, its
          // number given (a review: "'90\xC2\xB0' is not a decimal number" alone). Any other unit
          // gets no number: `1kHz`, `--record-ms 5s` or `--rate 100s` would be told one off by a
          // factor or in the wrong unit, and a letter typed for a digit (`9O`) a wrong one (re-tests).
          std::size_t n = v.size();
          while (n > 0 && !decimal_text(v.substr(0, n), whole, is_unsigned)) --n;
          std::string rest = v.substr(n);
          if (!rest.empty() && rest.front() == ' ') rest.erase(0, 1);
          const std::string typed = rest == "\xC2\xB0" || rest == "deg" || rest == "degrees" ? "deg"
                                    : rest == "Hz" || rest == "hz"                        ? "Hz"
                                                                                          : rest;
          std::string hint;
          if (n > 0 && !rest.empty() && typed == unit) {
            hint = "; give the number alone, without " + std::string(rest == "\xC2\xB0" ? "the degree sign" : "its unit") +
                   ": " + v.substr(0, n);
          } else if (n > 0 && unit == "fraction" && rest == "%") {
            // A per cent where the option takes a fraction (`--confidence 68%`): the fraction.
            char f[32];
            std::snprintf(f, sizeof f, "%.12g", std::strtod(v.substr(0, n).c_str(), nullptr) / 100);
            hint = "; give a fraction, not a per cent: " + v.substr(0, n) + "% is " + f;
          }
          return "'" + rig::shown_text(v) + "' is not a decimal " +
                 // No bound here: the option's own check states its range (--count >= 1 said
                 // ">= 0" for '01', a review).
                 (is_unsigned ? "whole number (no sign, no leading zero)"
                              : whole ? "whole number (no leading zero)" : "number") +
                 hint;
        },
        ""));
    // Past 64 bits CLI11 took the largest value there is (`--seed 99999999999999999999999` ran
    // seed 18446744073709551615, a technician's review). Last among the checks: an option with a
    // range of its own says it first (`--unit 99999999999999999999`: "not in range 1 to 247").
    if (whole)
      o->check(CLI::Validator(
          [is_unsigned](std::string& v) -> std::string {
            if (fits_64_bits(v, is_unsigned)) return std::string();
            const bool negative = !v.empty() && v[0] == '-';
            // No range claimed: an option may check its own later, in its command (a re-test:
            // --memory-mib said "0 to 18446744073709551615" and takes 1 to 1048576).
            return "'" + rig::shown_ascii(v) + "' is too " + (negative ? "small" : "large") + " (past 64 bits)";
          },
          ""));
  }
  for (CLI::App* sub : app.get_subcommands({})) decimal_numbers_only(*sub);
}

// CLI11's "Could not convert: --threads = 4294967297": a whole number the checks above passed
// (decimal, within 64 bits) that the option's narrower type cannot hold. Said as the 64-bit case
// is (a review: the raw "Could not convert" for --threads past 2^32); any other error as CLI11 words it.
std::string conversion_said(const CLI::Error& e) {
  const std::string what = e.what();
  const std::string head = "Could not convert: ";
  const std::size_t eq = what.find(" = ");
  if (dynamic_cast<const CLI::ConversionError*>(&e) == nullptr || what.rfind(head, 0) != 0 || eq == std::string::npos)
    return what;
  const std::string name = what.substr(head.size(), eq - head.size()), v = what.substr(eq + 3);
  if (!decimal_text(v, true, false)) return what;
  return name + ": '" + v + "' is too " + (v[0] == '-' ? "small" : "large") + " for this option";
}

// An option that takes text (a path, a URL, a name) refuses an empty value: `--out "$DIR"` with
// DIR unset wrote the run into ./runs/, `--db ""` recorded into the default database and
// `rig history --serial ""` filtered nothing, each with exit 0 (a review). No text option of rig
// gives "" a meaning of its own (each one's default is what leaving it out gives), so none is
// exempt; one that did would be listed here with why.
void no_empty_text(CLI::App& app) {
  for (CLI::Option* o : app.get_options()) {
    const std::string shown = o->get_type_name();  // "TEXT", or with a check's text: "TEXT:FILE"
    if (shown.substr(0, shown.find(':')) != "TEXT") continue;
    o->transform(CLI::Validator([](std::string& v) { return v.empty() ? std::string("empty value") : std::string(); },
                                ""));
  }
  for (CLI::App* sub : app.get_subcommands({})) no_empty_text(*sub);
}

// A process started with stdin, stdout or stderr closed (`rig run <&- >&- 2>&-`, a careless
// service unit) gets its first open() on descriptor 0, 1 or 2: the raw capture became fd 2 and
// the progress display was written into it (a review). Each closed one is opened on /dev/null
// before anything else, as coreutils and daemons do; without /dev/null nothing is safe. A closed
// stdout of a subcommand that ends by itself is opened on /dev/full instead: what the command prints
// fails to be written, and standard_output_failed() says so (exit 2) where /dev/null dropped it
// with exit 0 (a review: `rig analyze ... >&-`); one that prints nothing there is not troubled.
// `run`'s records are its files and its console may go away; `plant serve` and `dut stream` run
// until stopped, as services may with stdout closed (a stop of a server then read exit 2, hours
// on, a code review): /dev/null, as before.
// `rig run` and `rig capture import`: their records are their files, what they print is not their
// result (the stdout checks below and at start-up ask the same). A dry run's plan is its only
// result (`rig run --dry-run > /dev/full` was exit 0 with no plan seen: a review).
bool records_are_files(std::string_view subcommand, bool dry_run) {
  return (subcommand == "run" && !dry_run) || subcommand == "capture";
}
// `rig table stop` and `quick-stop`: the stop is the result (its exit code says whether it was
// delivered), the line printed only its confirmation; a stop sent from a script with stdout
// closed exited 2 ("usage error") after it went out (a technician's re-test). Known once parsed
// (a word scan took `--hardware stop` for one: a code review).
bool a_stop(std::string_view subcommand, std::string_view action) {
  return subcommand == "table" && (action == "stop" || action == "quick-stop");
}

// A line asking for the help or the version has them as its output, whatever its subcommand
// (`rig run --help >&-` was exit 0 with nothing written, `rig --help run >&-` exit 2).
bool console_may_go(int argc, char** argv) {
  if (argc < 2) return false;
  bool dry_run = false;
  for (int i = 1; i < argc && std::string_view(argv[i]) != "--"; ++i) {
    const std::string_view w = argv[i];
    if (w == "--help" || w == "-h" || w == "--version") return false;
    // As CLI11 reads the flag: `--dry-run`, or `--dry-run=VALUE` with VALUE not false (a review:
    // `--dry-run=true >&-` had its plan dropped, exit 0).
    if (w == "--dry-run") dry_run = true;
    else if (w.rfind("--dry-run=", 0) == 0) {
      const std::string_view v = w.substr(10);
      dry_run = !(v == "false" || v == "0" || v == "no" || v == "off" || v == "-1");
    }
  }
  const std::string_view first = argv[1];
  if (records_are_files(first, dry_run)) return true;
  if (first != "plant" && first != "dut") return false;
  for (int i = 2; i < argc; ++i)
    if (std::string_view(argv[i]) == (first == "plant" ? "serve" : "stream")) return true;
  return false;
}
void standard_descriptors_open(bool console_may_go) {
  for (int fd = 0; fd <= 2; ++fd) {
    if (::fcntl(fd, F_GETFD) != -1) continue;
    const bool full = fd == 1 && !console_may_go;
    const int got = ::open(full ? "/dev/full" : "/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
    if (got != fd && full) {  // no /dev/full: as before
      if (got >= 0) ::close(got);
      if (::open("/dev/null", O_WRONLY) == fd) continue;
    }
    if (got != fd) std::_Exit(rig::kExitHardware);  // cannot even say so: stderr is closed
    if (fd == 1) rig::cli::stdout_closed() = full;
  }
}

// A signal that ends a subcommand without a watcher of its own (analyze, filter, report,
// history, capture, verify) is exit 3 as every aborted subcommand's (docs/contracts.md): they
// ended with the shell's 130, 143 or 129 (a review). `run`, `table`, `dut` and `plant` take
// the signals on their SignalWatcher's thread (blocked there, so this handler never runs). A
// signal the process started with ignored (`nohup`, a background job's SIGINT) stays ignored,
// but for the SIGINT, SIGTERM and SIGQUIT of the actions whose watcher takes them regardless:
// this handler takes them until it exists (takes_ignored_signals).
extern "C" void abort_on_signal(int sig) {
  // `rig run` past its verdict: its exit code stands (what is left is its closing table's write).
  if (const int verdict = rig::cli::g_verdict_exit.load(); verdict >= 0) {
    constexpr char late[] = "rig: a signal after the passport was final: its exit code stands\n";
    [[maybe_unused]] ssize_t w = ::write(STDERR_FILENO, late, sizeof late - 1);
    ::_exit(verdict);
  }
  const char* text = sig == SIGINT    ? "rig: aborted: SIGINT\n"
                     : sig == SIGTERM ? "rig: aborted: SIGTERM\n"
                     : sig == SIGQUIT ? "rig: aborted: SIGQUIT\n"
                                      : "rig: aborted: SIGHUP\n";
  std::size_t n = 0;
  while (text[n] != '\0') ++n;
  [[maybe_unused]] ssize_t w = ::write(STDERR_FILENO, text, n);
  // A staged output half written (app/abort_cleanup.hpp) goes, and its note is said.
  if (const rig::cli::AbortCleanup* c = rig::cli::g_abort_cleanup.load()) {
    ::unlink(c->path);
    for (n = 0; c->note[n] != '\0'; ++n) {
    }
    w = ::write(STDERR_FILENO, c->note, n);
  }
  ::_exit(rig::kExitAborted);
}

// The commands that take SIGINT, SIGTERM and SIGQUIT on a SignalWatcher (`rig run`, `table home`
// and `move`, `dut stream` and `loop-test`, `plant serve`) take them even when the process started
// with them ignored (a script's `rig run ... &`), but only from the moment the watcher exists:
// one that came in the milliseconds before was dropped, and the run went on to PASS (a
// technician's review, `kill -INT` 2-5 ms after the start). Taken by this handler until then. The
// others (a `rig table quick-stop` a script guards with `trap '' INT`) keep an ignored signal
// ignored (a code review). A word scan, before anything is parsed: the action is the first word
// that is not an option nor the value of one (`--hardware move` names a file: a review found the
// guard lost so); an option that takes no value before the action makes the scan miss it, which
// costs only the watcher's few milliseconds, as before.
bool takes_ignored_signals(int argc, char** argv) {
  if (argc < 2) return false;
  const std::string_view first = argv[1];
  if (first == "run") return true;
  for (int i = 2; i < argc; ++i) {
    const std::string_view w = argv[i];
    if (w.starts_with("-")) {
      if (w.find('=') == std::string_view::npos) ++i;  // its value
      continue;
    }
    return (first == "table" && (w == "home" || w == "move")) || (first == "dut" && (w == "stream" || w == "loop-test")) ||
           (first == "plant" && w == "serve");
  }
  return false;
}

void aborted_by_signals(bool take_ignored) {
  // A file size limit (`ulimit -f`) is a write that fails (EFBIG), said and handled as a full disk
  // is, not a kill that leaves staged files and says nothing (a re-test: exit 153).
  ::signal(SIGXFSZ, SIG_IGN);
  for (const int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT}) {
    struct sigaction was {};
    if (::sigaction(sig, nullptr, &was) != 0) continue;
    // SIGHUP ignored is nohup's request, which every subcommand keeps.
    if (was.sa_handler == SIG_IGN && (sig == SIGHUP || !take_ignored)) continue;
    struct sigaction now {};
    now.sa_handler = abort_on_signal;
    sigemptyset(&now.sa_mask);
    ::sigaction(sig, &now, nullptr);
  }
}

// As early as a dynamically linked program can: the executable's .preinit_array runs once the
// loader has mapped and relocated every library, before any library's or this program's static
// initialisers (about 10 ms of a `rig` start here went to those, before main). What comes before
// it, the kernel's exec and the loader's own work, is the window left: an ignored signal sent
// then is gone.
extern "C" void rig_take_signals_early(int argc, char** argv, char**) {
  aborted_by_signals(takes_ignored_signals(argc, argv));
}
[[gnu::section(".preinit_array"), gnu::used]] void (*const rig_preinit_signals)(int, char**,
                                                                                 char**) = rig_take_signals_early;

// Edits (insertions, deletions, substitutions, adjacent swaps) that turn a into b: the optimal
// string alignment distance, enough to catch a typed option's slip ("--moddbus", "--porfile").
std::size_t edits(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] != b[j - 1] ? 1 : 0)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

// The candidate nearest `word`, "" when none is within two edits (one for a word of up to four
// letters) or the word is itself one of them.
std::string nearest(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = word.size() <= 4 ? 2 : 3;
  for (const std::string& c : candidates)
    if (const std::size_t d = edits(word, c); d > 0 && d < best_d) best_d = d, best = c;
  return best;
}

// The long option of the chosen commands nearest `word` ("--moddbus" -> "--modbus").
std::string nearest_option(const std::vector<const CLI::App*>& chain, std::string word) {
  if (const auto eq = word.find('='); eq != std::string::npos) word.resize(eq);
  while (!word.empty() && word.front() == '-') word.erase(0, 1);
  // rig's own options (--version) are taken only before a subcommand, so a subcommand's line is
  // offered its commands' options alone; and never the word typed (it exists, but not there).
  std::vector<std::string> names;
  for (std::size_t i = chain.size() > 1 ? 1 : 0; i < chain.size(); ++i)
    for (const CLI::Option* o : chain[i]->get_options())
      for (const std::string& name : o->get_lnames()) names.push_back(name);
  const std::string best = nearest(word, names);
  return best.empty() ? best : "--" + best;
}

// "; did you mean X?" or nothing.
std::string did_you_mean(const std::string& near) { return near.empty() ? near : "; did you mean " + near + "?"; }

// Whether what was printed on standard output could not all be written (`> /dev/full`), said on
// stderr. A reader that went away (SIGPIPE ignored by the parent, so it is EPIPE here) is no
// failure.
bool standard_output_failed() {
  // A stream already failed (a line flushed by std::endl) keeps the errno its write left, as
  // nothing else ran since (`--version > /dev/full` said no reason, a code review).
  const int earlier = !std::cout ? errno : 0;
  errno = 0;
  std::cout.flush();
  const bool failed = !std::cout || std::fflush(stdout) != 0 || std::ferror(stdout);
  const int e = errno != 0 ? errno : earlier;
  if (!failed || e == EPIPE) return false;
  if (rig::cli::stdout_closed())
    std::cerr << "rig: output error: standard output is closed (the command was started with it closed, >&-): what "
                 "the command printed was not written\n";
  else
    std::cerr << "rig: output error: standard output: write failed" << (e ? std::string(": ") + std::strerror(e) : "")
              << " (what the command printed is incomplete)\n";
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  standard_descriptors_open(console_may_go(argc, argv));
  // The abort signals are taken already (rig_take_signals_early, before main).
  // A wait for another process's lock on the history is said while it lasts, not only when it
  // ends 10 s later (a `rig history` sat silent: a review).
  rig::history::set_lock_wait_notice([](const std::string& where, int limit_ms) {
    std::fprintf(stderr, "rig: %s is locked by another process (a write or a backup holding it): waiting up to %g s\n",
                 where.c_str(), limit_ms / 1000.0);
  });
  CLI::App app{"rig: acceptance test rig for quartz pendulum accelerometers (U10/U20 method)"};
  app.set_version_flag("--version", std::string("rig ") + RIG_VERSION);
  app.require_subcommand(1);
  int rc = rig::kExitPass;
  rig::cli::add_run(app, rc);
  rig::cli::add_analyze(app, rc);
  rig::cli::add_plant(app, rc);
  rig::cli::add_table(app, rc);
  rig::cli::add_dut(app, rc);
  rig::cli::add_filter(app, rc);
  rig::cli::add_report(app, rc);
  rig::cli::add_history(app, rc);
  rig::cli::add_capture(app, rc);
  rig::cli::add_verify(app, rc);
  decimal_numbers_only(app);
  no_empty_text(app);
  // A usage error is said with its kind, as every other exit-2 message is (it was CLI11's bare
  // text, "--rate: '0x10' is not a decimal number", which a script keyed on "rig: " missed).
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return std::string("rig: usage error: ") + conversion_said(e) + "\nRun with --help for more information.\n";
  });
  try {
    app.parse(argc, argv);
    // What a subcommand printed is its output (the summary of `rig analyze`, a history listing):
    // one that could not be written (`> /dev/full`) ended in exit 0 with nothing said (an
    // instrument engineer's review). Exit 2, as a --json file that cannot be written is. Not
    // `rig run`, whose records are its files (it ignores SIGPIPE: its console may go away), nor
    // `rig capture import`, whose capture is its record (exit 2 with the capture written, and
    // the retry refused for the file that exists: a re-test), nor a closed pipe (SIGPIPE ends
    // the others as it ends any filter).
    const CLI::App* chosen = app.get_subcommands().empty() ? nullptr : app.get_subcommands().front();
    const CLI::App* action = chosen && !chosen->get_subcommands().empty() ? chosen->get_subcommands().front() : nullptr;
    const bool dry_run =
        chosen && chosen->get_name() == "run" && chosen->get_option("--dry-run")->as<bool>();  // its value, not its count
    if (!chosen || !(records_are_files(chosen->get_name(), dry_run) ||
                     (action && a_stop(chosen->get_name(), action->get_name()))))
      if (standard_output_failed() && rc == rig::kExitPass) rc = rig::kExitUsage;  // another exit code says more
  } catch (const CLI::ParseError& e) {
    // `rig bogus`, `rig table spin`: CLI11 takes an unknown word where a subcommand belongs for a
    // stray argument and reports only the missing subcommand; name the word instead, with the
    // subcommands there are. The deepest subcommand the line chose is the one missing its own.
    CLI::App* at = &app;
    std::string path = "rig";
    std::vector<const CLI::App*> chain{&app};  // rig and each subcommand the line chose
    while (!at->get_subcommands().empty()) {
      at = at->get_subcommands().front();
      path += " " + at->get_name();
      chain.push_back(at);
    }
    // Only the two errors CLI11 words that way; any other (a bad value, a missing one) is its own.
    const bool missing_or_extra =
        dynamic_cast<const CLI::RequiredError*>(&e) != nullptr || dynamic_cast<const CLI::ExtrasError*>(&e) != nullptr;
    std::vector<std::string> rest = at->remaining();
    if (rest.empty() && at != &app && !app.remaining().empty()) {  // the stray word was given to rig itself
      rest = app.remaining();
      if (rest.front().rfind('-', 0) == 0) {
        std::cerr << "rig: usage error: unknown option '" << rig::shown_ascii(rest.front()) << "'"
                  << did_you_mean(nearest_option({&app}, rest.front())) << " (see rig --help)\n";
        return rig::kExitUsage;
      }
    }
    if (missing_or_extra && at->get_require_subcommand_min() > 0 && at->get_subcommands().empty()) {
      const std::string word = rest.empty() ? std::string() : rest.front();
      std::string choices = " (one of:";
      std::vector<std::string> names;
      for (const CLI::App* s : at->get_subcommands({})) names.push_back(s->get_name()), choices += ' ' + s->get_name();
      choices += "; see " + path + " --help)\n";
      // "rig: usage error: " first, as every other exit-2 message of the command line (a script keys on it).
      std::cerr << "rig: usage error: " << (at == &app ? std::string() : path + ": ");
      if (word.empty()) std::cerr << "a subcommand is required" << choices;
      else if (word.rfind('-', 0) == 0)
        std::cerr << "unknown option '" << rig::shown_ascii(word) << "'" << did_you_mean(nearest_option(chain, word))
                  << " (see " << path << " --help)\n";
      else std::cerr << "unknown subcommand '" << rig::shown_ascii(word) << "'" << did_you_mean(nearest(word, names)) << choices;
      return rig::kExitUsage;
    }
    // An option no chosen command has (`rig table status --jsn`): CLI11 lists every word it did not
    // take, backwards ("The following arguments were not expected: 127.0.0.1:502 --moddbus");
    // name the option as typed instead, with the nearest one there is (a review).
    if (dynamic_cast<const CLI::ExtrasError*>(&e) != nullptr) {
      std::vector<std::string> extra;
      for (const CLI::App* a : chain)
        for (const std::string& w : a->remaining()) extra.push_back(w);
      const auto is_option = [](const std::string& w) {
        return w.size() > 1 && w.front() == '-' && !std::isdigit(static_cast<unsigned char>(w[1])) && w[1] != '.';
      };
      if (const auto opt = std::find_if(extra.begin(), extra.end(), is_option); opt != extra.end()) {
        const std::string near = nearest_option(chain, *opt);
        std::string others;  // the other words not taken (an extra file name), as CLI11 listed them
        for (const std::string& w : extra)
          if (&w != &*opt) others += (others.empty() ? "" : " ") + ("'" + rig::shown_ascii(w) + "'");
        std::cerr << "rig: usage error: " << path << ": unknown option '" << rig::shown_ascii(*opt) << "'"
                  << (others.empty() ? std::string() : " (and not taken: " + others + ")")
                  << did_you_mean(near) << " (see " << path
                  << " --help)\n";
        return rig::kExitUsage;
      }
    }
    // --help/--version exit 0 (2 when what they print cannot be written); usage errors exit 2
    const int r = app.exit(e);
    return r == 0 && !standard_output_failed() ? 0 : rig::kExitUsage;
  } catch (const rig::ConfigError& e) {  // InputError, InUseError too: a usage-class error
    std::cerr << rig::cli::error_prefix(e) << e.what() << "\n";
    return rig::kExitUsage;
  } catch (const rig::AbortedError& e) {
    std::cerr << rig::cli::error_prefix(e) << e.what() << "\n";
    return rig::kExitAborted;
  } catch (const std::exception& e) {  // HardwareError, NotReadyError and the unforeseen
    std::cerr << rig::cli::error_prefix(e) << e.what() << "\n";
    return rig::kExitHardware;
  }
  return rc;
}
