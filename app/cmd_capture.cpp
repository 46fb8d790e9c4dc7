// `rig capture import LOG --hardware FILE --out CAPTURE`: a candump log (can-utils
// `candump -l` files, `candump -L` output) turned into the rig's capture file through
// the hardware file's [dut] stream description (its DBC and [dut.stream], or the rig
// protocol), with the reassembly's report: gaps located, duplicates, lines that could not
// be read. `rig analyze CAPTURE --input capture` and the report then work on logs
// recorded by can-utils or any tool writing that format.
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <csignal>
#include <cerrno>
#include <cstring>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <ctime>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "app/abort_cleanup.hpp"
#include "app/commands.hpp"
#include "app/hardware_file.hpp"
#include "app/number_option.hpp"
#include "app/output_file.hpp"
#include "app/serial_option.hpp"
#include "firmware_link/candump_log.hpp"
#include "firmware_link/connect.hpp"
#include "firmware_link/dbc.hpp"
#include "firmware_link/dbc_stream.hpp"
#include "rig/capture/capture.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"
#include "rig/core/path_kind.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::cli {

namespace {

struct ImportArgs {
  std::string log, hardware, out, serial, orientation = "U10", phase = "import", iface;
  std::optional<double> rate_hz;  // none: the stream's (rate_hz of [dut.stream], 1000 for the rig protocol)
  std::size_t from_line = 1;      // the log's first line to import (the rest after a DUT restart)
};

// The log's clock, where its time stamps are one: absolute (candump -l, -L, -ta: seconds since
// the epoch). Relative stamps (-td deltas, -tz) are not checked against (a -td log's deltas
// read as a clock hid every pause after the first, a review).
bool a_clock(double t_s) { return t_s > 1e8; }

// A stamp this far behind the latest is out of order: candump's stamps are the kernel's receive
// times, in order on one socket; a log merged from several interfaces may swap neighbours by less.
constexpr double kBackS = 1e-3;

// A pause the counter cannot span: the log's clock says at least a second went by (host-side
// buffering bunches frames by milliseconds, never a second) and at least half the counter's
// period, so the widening cannot tell how many periods passed. "" when it can.
std::string pause_too_long(const link::StreamReassembler& r, double dt_s, double rate_hz) {
  if (!r.started()) return {};
  const double half = std::ldexp(1.0, r.counter_bits() - 1);
  if (dt_s < 1 || dt_s * rate_hz < half - r.window()) return {};
  return fmt::format("{:.6g} s passed since the stream's last frame ({:.6g} samples at {} Hz), more than half the "
                     "{}-bit counter's period: how many periods went by cannot be told",
                     dt_s, dt_s * rate_hz, rate_hz, r.counter_bits());
}

// A counter that leapt ahead further than the log's clock went (a DUT that restarted after its
// counter had passed half its period widens to a leap forward, not back: it read as hours of
// lost samples in seconds of log, a review). The leap is allowed the clock's interval plus 5 %
// (a DUT's clock a little off; the rate check holds the whole log to 2 %) plus 0.25 s, a
// receiver's burst of frames stamped together; "" when it fits. It was four times the interval
// plus 2 s: a 12-bit counter that restarted 1.1 s short of its period imported as a 1096-sample
// gap 1 ms of log long, or after a pause of 0.5-2 s, every later sample 1.1 s late (reviews). A
// restart whose leap the clock's interval matches, within that, is not told from a gap.
constexpr double kBurstS = 0.25;
std::string leap_beyond_clock(const link::StreamReassembler& r, uint32_t counter, double dt_s, double rate_hz) {
  if (!r.started()) return {};
  const uint64_t s = r.widened(counter), top = r.highest_seq();
  if (s <= top + r.window()) return {};
  const double leap_s = static_cast<double>(s - top) / rate_hz;
  if (leap_s <= 1.05 * dt_s + kBurstS) return {};
  return fmt::format("the stream's counter leapt {} samples ({:.6g} s at {} Hz) where the log's clock moved {:.6g} s "
                     "(the DUT restarted? or its rate is not {} Hz: --rate)",
                     s - top, leap_s, rate_hz, dt_s, rate_hz);
}

// A frame further behind than any reordering (the reorder window): a stray late frame, or the
// first of a counter that went back (the DUT restarted). The frames after it tell which.
bool far_behind(const link::StreamReassembler& r, uint32_t counter) {
  return r.started() && r.widened(counter) + r.window() < r.next_seq();
}

// A log's absolute time (seconds since the epoch) as ISO 8601 UTC; "" for relative times.
std::string iso8601(double t_s) {
  if (!a_clock(t_s)) return {};  // candump -td / -tz style relative stamps
  const std::time_t t = static_cast<std::time_t>(std::floor(t_s));
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[40];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

// What an earlier import left beside --out: an OUT.part-PID no import writes now. A capture it
// kept there (--out taken meanwhile, or the rename refused: "kept as") is whole; one killed
// outright (SIGKILL, a power cut) is a partial file: each said as what it is, neither removed
// (the name is all that says whose it is). An import holds its staged file locked (flock) while
// it writes; a file is left over when no process of its number runs, or when one does that holds
// no lock on it and is not a rig (its number reused). A rig of that number is taken as writing
// it, whatever its executable's path says now (a reinstall renames it "... (deleted)": a code
// review found a live import's file called partial).
bool staged_is_written(const std::string& path, pid_t pid) {
  if (::kill(pid, 0) != 0 && errno == ESRCH) return false;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return true;  // cannot tell: taken as written
  const bool held = ::flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  ::close(fd);
  if (held) return true;
  std::ifstream comm("/proc/" + std::to_string(pid) + "/comm");
  std::string name;
  return !comm || !std::getline(comm, name) || name == "rig";
}

// --out's folder as --out names it ("." for a bare name), and the staged name's prefix there: one
// spelling for the import that writes OUT.part-PID and the one that looks for those left.
std::string folder_of(const std::string& out) {
  const std::filesystem::path p(out);
  return p.has_parent_path() ? p.parent_path().string() : std::string(".");
}
std::string staged_prefix(const std::string& out) { return out + ".part-"; }

void note_left_staged(const std::string& out) {
  namespace fs = std::filesystem;
  const std::string prefix = fs::path(staged_prefix(out)).filename().string();
  std::error_code ec;
  for (fs::directory_iterator it(folder_of(out), ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    pid_t pid = 0;
    const char* const last = name.data() + name.size();
    const auto [at, err] = std::from_chars(name.data() + prefix.size(), last, pid);
    if (err != std::errc() || at != last || pid <= 0 || pid == ::getpid()) continue;
    const std::string staged = staged_prefix(out) + name.substr(prefix.size());  // as the import named it
    if (staged_is_written(staged, pid)) continue;
    if (capture::ends_closed(staged))
      std::fprintf(stderr,
                   "rig capture import: %s is a whole capture an earlier import kept under its staged name (no "
                   "import writes it now): rename it to use it, to a name other than %s, which this import writes\n",
                   staged.c_str(), out.c_str());
    else
      std::fprintf(stderr,
                   "rig capture import: %s is left from an import that did not finish (no import writes it now): a "
                   "partial file, not a capture; remove it\n",
                   staged.c_str());
  }
}

// The capture is written under a staged name beside --out (OUT.part-PID, this process's own: two
// imports to one name set each other's file aside, a code review) and takes --out's name only
// where the import keeps it: a stop (SIGTERM), a full disk or a refusal left a partial file under
// the name asked for, which rig analyze read as a shorter record and a retry was refused over (a
// technician's review). Unwound by an error, the staged file goes and stderr says --out was not
// written; so does a signal (SIGINT, SIGTERM, SIGHUP). A SIGKILL leaves OUT.part-PID, never OUT.
class StagedCapture {
 public:
  explicit StagedCapture(std::string out)
      : out_(std::move(out)), staged_(staged_prefix(out_) + std::to_string(::getpid())),
        staged_name_(std::filesystem::path(staged_).filename().string()),
        not_written_("rig capture import: " + out_ + " not written (the import did not finish)\n"),
        on_signal_(staged_, not_written_) {
    // The folder held open: the staged file is removed from it even where it was renamed meanwhile
    // (a code review: "nothing kept" while OUT.part-PID stayed in the folder's new place).
    folder_ = folder_of(out_);
    folder_fd_ = ::open(folder_.c_str(), O_PATH | O_DIRECTORY | O_CLOEXEC);
  }
  StagedCapture(const StagedCapture&) = delete;
  StagedCapture& operator=(const StagedCapture&) = delete;
  ~StagedCapture() {
    if (!settled_) {
      remove_staged();
      if (std::uncaught_exceptions() > unwinding_) std::fputs(not_written_.c_str(), stderr);
    }
    if (folder_fd_ >= 0) ::close(folder_fd_);
    if (lock_fd_ >= 0) ::close(lock_fd_);
  }
  const std::string& path() const { return staged_; }
  // Held while this import writes, once its file exists: another import to --out sees it written
  // (note_left_staged), whatever this process's executable is called by then.
  void hold() {
    lock_fd_ = ::open(staged_.c_str(), O_RDONLY | O_CLOEXEC);
    if (lock_fd_ >= 0) ::flock(lock_fd_, LOCK_EX | LOCK_NB);
  }
  // The staged file goes: nothing under --out.
  void drop() {
    if (settled_) return;
    remove_staged();
    settled_ = true;
    on_signal_.release();
  }
  // The staged file takes --out's name, never over a file that appeared there meanwhile, nor in a
  // folder that is no longer where --out says. Again (settled): nothing.
  void keep() {
    if (settled_) return;
    settled_ = true;
    if (!folder_in_place()) {
      remove_staged();
      on_signal_.release();
      throw ConfigError("rig capture import: --out " + out_ + ": its folder " + folder_ + " was removed or renamed "
                        "during the import: the capture written there is removed, nothing kept (the log is as it "
                        "was: import it again)");
    }
    int e = ::renameat2(AT_FDCWD, staged_.c_str(), AT_FDCWD, out_.c_str(), RENAME_NOREPLACE) == 0 ? 0 : errno;
    // A file system without RENAME_NOREPLACE: a hard link does not replace either.
    if (e == EINVAL || e == ENOSYS) {
      e = ::link(staged_.c_str(), out_.c_str()) == 0 ? 0 : errno;
      if (e == 0) ::unlink(staged_.c_str());
    }
    on_signal_.release();  // after the rename: a signal before it still takes the staged file
    if (e == 0) return;
    if (e == EEXIST)
      throw ConfigError("rig capture import: --out " + out_ + ": a file appeared there during the import; the capture "
                        "is kept as " + staged_);
    // "Kept as" only where it is (a review: it named a path that was gone).
    struct stat st {};
    const bool there = ::lstat(staged_.c_str(), &st) == 0;
    throw ConfigError("rig capture import: --out " + out_ + ": cannot put the capture in place (" + std::strerror(e) +
                      ")" + (there ? "; it is kept as " + staged_ : std::string("; the staged capture is gone too, nothing kept")));
  }

 private:
  // The folder --out names is still the one the import opened (not removed, not renamed away).
  bool folder_in_place() const {
    struct stat now {}, opened {};
    if (folder_fd_ < 0) return true;  // not opened: nothing to compare, the rename says
    return ::stat(folder_.c_str(), &now) == 0 && ::fstat(folder_fd_, &opened) == 0 && now.st_dev == opened.st_dev &&
           now.st_ino == opened.st_ino;
  }
  void remove_staged() {
    if (folder_fd_ >= 0) ::unlinkat(folder_fd_, staged_name_.c_str(), 0);
    else ::unlink(staged_.c_str());
  }

  std::string out_, staged_, staged_name_, folder_;
  std::string not_written_;  // said on an error's unwinding and by a signal's exit alike
  RemoveOnAbort on_signal_;  // a signal's exit (main.cpp) unlinks the staged file too
  int folder_fd_ = -1;
  int lock_fd_ = -1;
  bool settled_ = false;
  int unwinding_ = std::uncaught_exceptions();
};

int cmd_import(const ImportArgs& a) {
  if (a.orientation != "U10" && a.orientation != "U20")
    throw ConfigError("rig capture import: --orientation must be U10 or U20, got '" + a.orientation + "'");
  // The header's rate is checked as every reader of a capture checks it (capture.hpp).
  if (a.rate_hz && !(*a.rate_hz >= capture::kMinRateHz && *a.rate_hz <= capture::kMaxRateHz))
    throw ConfigError("rig capture import: --rate " + fmt::format("{}", *a.rate_hz) + ": must be in [" +
                      fmt::format("{}", capture::kMinRateHz) + ", " +
                      fmt::format("{}", capture::kMaxRateHz) + "] Hz");
  // A folder as the log opened fine and failed at its first read, exit 4 without its name (an
  // instrument engineer's review); a FIFO or a pipe's /dev/fd path is still read.
  switch (path_kind(a.log, "candump log")) {
    case PathKind::missing: throw ConfigError(shown_text(a.log) + ": no such candump log");
    case PathKind::directory: throw ConfigError(shown_text(a.log) + ": is a folder, not a candump log (give one file)");
    default: break;
  }
  check_new_file(a.out, "rig capture import: --out");
  const toml::table hw = load_hardware_file(a.hardware, {"dut"});
  const toml::table& dut = *cfg::get_table(hw, "dut", true);
  const link::LinkOptions lo = link::link_options(dut);  // validates [dut], reads its stream
  const auto decoder = lo.stream ? lo.stream : link::stream_decoder_from_config(dut);
  const std::string own_can = dut.contains("can") ? cfg::get_string(dut, "can") : "";  // the DUT's interface, if named
  // Nothing waits on a log's first sample: the start is held for the reorder window (a first
  // sample logged a few frames late takes its place, not a duplicate's).
  link::StreamReassembler reasm = decoder->make_reassembler(lo.reorder_window, true);

  std::ifstream in(a.log);
  if (!in) throw ConfigError(a.log + ": cannot open candump log");

  capture::Header h;
  h.serial = a.serial;
  h.phase = a.phase;
  h.orientation = a.orientation;
  h.rate_hz = a.rate_hz ? *a.rate_hz : decoder->rate_hz();
  // The header is written first; its start time is the first frame's on the stream's interface
  // (--iface, else the interface of the log's first stream frame: a log of several is refused
  // below unless one is chosen), so the log is read up to there first (cheap next to decoding).
  std::string stream_iface = a.iface;
  {
    std::string line;
    bool too_long = false;
    std::vector<std::pair<std::string, double>> first_t;  // each interface's first frame
    std::vector<link::StreamPart> ps;
    for (std::size_t ln = 1; link::read_log_line(in, line, too_long); ++ln) {
      const auto lf = link::parse_candump_line(line);
      if (too_long || ln < a.from_line || !lf || (!a.iface.empty() && lf->iface != a.iface)) continue;
      auto seen = std::find_if(first_t.begin(), first_t.end(), [&](const auto& f) { return f.first == lf->iface; });
      if (seen == first_t.end()) seen = first_t.insert(first_t.end(), {lf->iface, lf->t_s});
      ps.clear();
      if (!a.iface.empty() || (decoder->decode(lf->any, ps) && !ps.empty())) {
        stream_iface = lf->iface;
        h.started = iso8601(seen->second);
        break;
      }
    }
    if (h.started.empty() && !first_t.empty()) h.started = iso8601(first_t.front().second);  // no stream frame
    // No stream frame at all (another DUT's layout, only commands): the log's frames are still
    // counted as read on the [dut] can, or on the log's one interface, so the counts say "other
    // ids", not "other interfaces" (which sent a review after --iface instead of the DBC).
    if (stream_iface.empty() && !first_t.empty()) {
      const bool own_logged =
          !own_can.empty() && std::any_of(first_t.begin(), first_t.end(), [&](const auto& f) { return f.first == own_can; });
      if (own_logged)
        stream_iface = own_can;
      else if (first_t.size() == 1)
        stream_iface = first_t.front().first;
    }
    in.clear();
    in.seekg(0);
  }
  const link::DbcStreamSpec& sp = decoder->spec();
  h.extra = {{"source", "candump log"},
             {"log", a.log},
             {"hardware", a.hardware},
             {"stream", {{"counter", sp.counter}, {"counter_bits", decoder->counter_bits()}, {"x", sp.x}, {"y", sp.y},
                         {"samples_per_frame", sp.samples_per_frame}}}};
  if (!stream_iface.empty()) h.extra["iface"] = stream_iface;  // lines without an interface column: none
  note_left_staged(a.out);
  StagedCapture staged(a.out);
  capture::Writer w(staged.path(), h);
  staged.hold();

  // frames: read on the stream's interface; elsewhere: on other interfaces, not read further
  uint64_t frames = 0, stream_frames = 0, other = 0, unreadable = 0, malformed = 0, elsewhere = 0;
  std::vector<std::string> problems;  // LOG:LINE: why, the first 20
  auto note = [&](std::size_t ln, const std::string& why) {
    if (problems.size() < 20) problems.push_back(a.log + ":" + std::to_string(ln) + ": " + why);
  };
  std::vector<link::StreamPart> parts;
  std::vector<Sample> buf(4096);
  auto drain = [&] {
    while (std::size_t n = reasm.pop(buf)) w.append(std::span<const Sample>(buf.data(), n));
  };
  std::string line, cut;  // cut: LOG:LINE: why the import stopped there
  std::size_t cut_line = 0;
  std::optional<double> last_t;  // the log's clock at the last stream frame (absolute stamps only)
  // The log's clock over the samples taken (absolute stamps only), held to the header's rate:
  // a 500 Hz log imported at 1000 Hz, or a counter read in the wrong byte order (764 506 samples
  // lost in 3 s), imported with exit 0 (an integrator's review).
  struct Stamp {
    double t_s;
    std::size_t line;
  };
  std::optional<Stamp> taken_first, taken_last;
  double longest_quiet_s = 0;  // the longest time between two frames taken: a pause, a logger's burst
  // Values the layout decodes outside their signal's DBC range, or not finite (a wrong byte
  // order read y as 1e17 g and NaN, exit 0: the same review). Not finite: nothing can analyse
  // it (exit 2); only outside the range: a wrong layout, or a DUT driven past its DBC's range.
  uint64_t implausible = 0, not_finite = 0;
  // LOG:LINE: signal = value unit (the DBC's range), of the first outside it and of the first not
  // finite (a NaN at line 501 was not located: only a range overshoot at line 10 was, a review).
  std::string first_implausible, first_not_finite;
  auto signal_of = [&](link::Channel c) -> const link::DbcSignal* {
    const std::string& name = c == link::Channel::X ? sp.x : sp.y;
    const auto dot = name.find('.');
    const link::DbcMessage* m = dot == std::string::npos ? nullptr : decoder->dbc().find(name.substr(0, dot));
    return m ? m->signal(name.substr(dot + 1)) : nullptr;
  };
  // Frames far behind the stream, held until the stream shows what they are: it goes on from
  // where it was (stray late frames), or the held counter carries on for more than the reorder
  // window (the counter went back: the DUT restarted). Two strays in a row are not a restart.
  struct Counts {  // what the lines from the first held frame on added, taken back at a cut there
    uint64_t frames, other, unreadable, malformed, back, elsewhere;
    std::size_t problems;
  };
  // Stream frames stamped earlier than the log's clock had reached (absolute stamps): lines out of
  // order, or a clock stepped back (an NTP step). Their samples go where their counter says; said,
  // since every pause and leap is judged on that clock.
  uint64_t back = 0;
  std::size_t back_line = 0;
  double back_s = 0;
  auto back_to = [&](const Counts& c) {  // at a cut: the count before it (the first named only if before it)
    back = c.back;
    if (back == 0) back_line = 0, back_s = 0;
  };
  struct Suspect {
    std::size_t line = 0;  // the first's
    uint32_t counter = 0;  // the first's
    uint32_t span = 0;     // the last held counter's distance past the first's
    Counts before{};
    std::vector<std::vector<link::StreamPart>> frames;
  };
  std::optional<Suspect> suspect;
  uint64_t late = 0, late_parts = 0;  // frames far behind the stream went on from: dropped, counted apart
  auto push = [&](const std::vector<link::StreamPart>& ps) {
    for (const auto& p : ps) reasm.push_part(p);
    drain();
  };
  auto drop_suspect = [&] {  // the stream went on: stray late frames (the reassembly drops them)
    if (!suspect) return;
    late += suspect->frames.size();
    const uint64_t d0 = reasm.stats().duplicates;
    for (const auto& f : suspect->frames) push(f);
    late_parts += reasm.stats().duplicates - d0;
    suspect.reset();
  };
  const uint32_t counter_mask = reasm.counter_mask();
  auto cut_at_restart = [&] {  // the held frames start the rest: counts back to their first line
    cut = fmt::format("{}:{}: the stream's counter went back from {} to {} (the DUT restarted?)", a.log, suspect->line,
                      reasm.highest_seq() & counter_mask, suspect->counter);
    cut_line = suspect->line;
    frames = suspect->before.frames;
    other = suspect->before.other;
    unreadable = suspect->before.unreadable;
    malformed = suspect->before.malformed;
    elsewhere = suspect->before.elsewhere;
    back_to(suspect->before);
    problems.resize(suspect->before.problems);
    stream_frames -= suspect->frames.size();
    suspect.reset();
  };
  // Without --iface, each interface that carries stream frames with its first line: a log of two
  // stations (`candump -l any`) interleaves two DUTs' streams, which imported as one under one
  // serial, exit 0 (a review).
  std::vector<std::pair<std::string, std::size_t>> ifaces;
  bool too_long = false;
  std::size_t lines = 0;  // the log's, for a --from-line past its end
  for (std::size_t ln = 1; link::read_log_line(in, line, too_long); ++ln) {
    lines = ln;
    if (ln < a.from_line) continue;
    if (too_long) {
      ++unreadable;
      note(ln, link::too_long_problem());
      continue;
    }
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const link::LogLine parsed = link::read_candump_line(line);
    if (parsed.kind != link::LogLineKind::Frame) {
      ++unreadable;
      note(ln, parsed.problem.rfind("not a candump", 0) == 0 ? parsed.problem : "not a candump frame line: " + parsed.problem);
      continue;
    }
    const link::LoggedFrame* lf = &parsed.frame;
    if (!a.iface.empty() && lf->iface != a.iface) {
      ++elsewhere;
      continue;
    }
    // Named: two counts of one type in another order compile silently (a code review caught it).
    const Counts here{.frames = frames,
                      .other = other,
                      .unreadable = unreadable,
                      .malformed = malformed,
                      .back = back,
                      .elsewhere = elsewhere,
                      .problems = problems.size()};
    parts.clear();
    std::string err;
    const bool stream = decoder->decode(lf->any, parts, &err);  // classic or CAN FD frames as logged
    if (!stream && lf->iface != stream_iface) {  // another interface's traffic (its stream frames are checked below)
      ++elsewhere;
      continue;
    }
    ++frames;
    if (!stream) {
      ++other;  // commands, heartbeats, other nodes' traffic
      continue;
    }
    if (a.iface.empty()) {  // one interface's stream: another's is another station's DUT
      if (std::none_of(ifaces.begin(), ifaces.end(), [&](const auto& i) { return i.first == lf->iface; }))
        ifaces.emplace_back(lf->iface, ln);
      if (ifaces.size() > 1) continue;  // mixed: the rest of the log is only read for its interfaces
    }
    if (!err.empty()) {
      ++malformed;
      note(ln, err);
      continue;
    }
    if (parts.empty()) {
      ++stream_frames;
      continue;
    }
    // A counter that cannot carry on ends this capture: what came before is kept and the rest
    // is another capture (--from-line), never spliced on as if no time had passed. The clock
    // moves forward only: a stamp out of line backwards is no pause of the next frame.
    double dt = 0;
    const bool timed = a_clock(lf->t_s) && last_t.has_value();  // a clock to hold the counter to
    if (a_clock(lf->t_s)) {
      if (last_t && lf->t_s > *last_t) dt = lf->t_s - *last_t;
      if (last_t && lf->t_s < *last_t - kBackS && back++ == 0) back_line = ln, back_s = *last_t - lf->t_s;
      if (!last_t || lf->t_s > *last_t) last_t = lf->t_s;
    }
    const uint32_t c = parts.front().counter & counter_mask;
    std::string why = pause_too_long(reasm, dt, h.rate_hz);
    if (why.empty() && timed && !suspect) why = leap_beyond_clock(reasm, c, dt, h.rate_hz);
    if (!why.empty()) {
      drop_suspect();
      cut = a.log + ":" + std::to_string(ln) + ": " + why;
      cut_line = ln;
      frames = here.frames;  // this line is the rest's
      back_to(here);
      break;
    }
    if (far_behind(reasm, c)) {
      const uint32_t ahead = suspect ? (c - suspect->counter) & counter_mask : 0;
      if (suspect && ahead > counter_mask / 2) drop_suspect();  // further back still: those were strays
      if (!suspect) suspect = Suspect{ln, c, 0, here, {}};
      else suspect->span = std::max(suspect->span, ahead);
      suspect->frames.push_back(parts);
      ++stream_frames;
      if (suspect->span >= reasm.window()) {  // it carried on past the window: it went back
        cut_at_restart();
        break;
      }
      continue;
    }
    drop_suspect();
    ++stream_frames;
    for (const link::StreamPart& p : parts) {
      if (!p.implausible) continue;
      const bool finite = std::isfinite(p.value_g);
      not_finite += !finite;
      if (implausible++ > 0 && (finite || not_finite > 1)) continue;
      const link::DbcSignal* sig = signal_of(p.channel);
      const double shown = sig ? p.value_g / decoder->scale_to_g(p.channel) : p.value_g;  // as the DBC's range has it
      std::string where = fmt::format("{}:{}: {} = {:.9g} {}", a.log, ln, p.channel == link::Channel::X ? sp.x : sp.y,
                                      shown, sig ? sig->unit : std::string("g"));
      if (sig && sig->min < sig->max) where += fmt::format(", its DBC range [{}|{}] {}", sig->min, sig->max, sig->unit);
      if (implausible == 1) first_implausible = where;
      if (!finite) first_not_finite = std::move(where);
    }
    if (a_clock(lf->t_s)) {
      if (!taken_first) taken_first = Stamp{lf->t_s, ln};
      if (taken_last && lf->t_s > taken_last->t_s) longest_quiet_s = std::max(longest_quiet_s, lf->t_s - taken_last->t_s);
      if (!taken_last || lf->t_s >= taken_last->t_s) taken_last = Stamp{lf->t_s, ln};
    }
    push(parts);
  }
  if (ifaces.size() > 1) {
    w.close();
    staged.drop();
    const std::string& own = own_can;
    std::string listed, names;
    bool own_among = false, unnamed = false;
    for (const auto& [name, first] : ifaces) {
      listed += fmt::format("{}{} (from {}:{})", listed.empty() ? "" : ", ",
                            name.empty() ? "lines without an interface column" : name, a.log, first);
      if (!name.empty()) names += (names.empty() ? "" : ", ") + name;
      own_among = own_among || (!own.empty() && name == own);
      unnamed = unnamed || name.empty();
    }
    const std::string found = "frames of the [dut] stream on " + listed;
    if (own_among) {
      std::fprintf(stderr, "%s: %s: importing %s's, the hardware file's [dut] can (--iface for another)\n",
                   a.log.c_str(), found.c_str(), own.c_str());
      ImportArgs on_own = a;
      on_own.iface = own;
      return cmd_import(on_own);
    }
    std::fprintf(stderr, "%s: %s: the log holds more than one station's stream (%s); give --iface with one of: %s%s; "
                 "%s not written\n", a.log.c_str(), found.c_str(),
                 own.empty() ? (a.hardware + "'s [dut] has no can to choose by").c_str()
                             : (a.hardware + "'s [dut] can is " + own).c_str(),
                 names.c_str(), unnamed ? " (lines without an interface cannot be chosen: split the log)" : "",
                 a.out.c_str());
    return kExitUsage;
  }
  // The log ends on held frames: a restart if their counter carried on, else strays.
  if (cut.empty() && suspect && suspect->span > 0) cut_at_restart();
  drop_suspect();
  const uint64_t tail = reasm.flush();
  drain();
  const LinkStats& st = reasm.stats();
  w.close();

  // The rate against the log's clock: the samples taken (with those lost between them) over the
  // time their frames span. A clock's drift is ppm; a logger's stamps come late by up to the
  // longest quiet time between frames (a burst, a pause the counter did not count), so the
  // tolerance is 2 % plus that over the span: a rate off by half or double still stands out. A
  // clock that stepped back (said above) gives no span to read.
  std::string rate_mismatch, clock_line;
  if (taken_first && taken_last && back == 0) {
    const double span_s = taken_last->t_s - taken_first->t_s;
    const double covered = static_cast<double>(w.samples_written() + st.lost);
    if (span_s >= 1.0 && covered >= 100) {
      const double log_rate = (covered - sp.samples_per_frame) / span_s;
      const double tolerance = 0.02 + longest_quiet_s / span_s;
      clock_line = fmt::format("the log's clock: {:.0f} samples ({} lost among them) in {:.6g} s, lines {} to {}: {:.6g} Hz",
                               covered, st.lost, span_s, taken_first->line, taken_last->line, log_rate);
      if (std::fabs(log_rate / h.rate_hz - 1) > tolerance)
        rate_mismatch = fmt::format(
            "{}: the log's clock gives {:.6g} Hz (lines {} to {}), the capture's rate would be {} Hz ({}), more than "
            "{:.3g} % apart: every tau would be off by a factor of {:.3g}. Check [dut.stream] rate_hz (or give --rate "
            "with the DUT's rate) and the counter signal's byte order and length (gaps {}, {} samples lost); a "
            "stream that paused without its counter, or a log of two streams, is imported in parts (--from-line); "
            "{} not written",
            a.log, log_rate, taken_first->line, taken_last->line, h.rate_hz,
            a.rate_hz ? "--rate" : "the hardware file's or the protocol's", 100 * tolerance, h.rate_hz / log_rate,
            st.gaps, st.lost, a.out);
    }
  }
  // A --from-line past the end (not the default 1 on an empty log, which is the case below).
  if (a.from_line > 1 && a.from_line > lines) {  // it read "no sample ... in 0 frame(s)" after a summary of nothing
    staged.drop();
    std::fprintf(stderr, "%s: --from-line %zu is past the log's end: it has %zu line(s); %s not written\n",
                 a.log.c_str(), a.from_line, lines, a.out.c_str());
    return kExitUsage;
  }
  // The counts are the stream interface's, with --iface or without (they differed: a review).
  // "LOG -> OUT" only where OUT is kept (it read so above a "not written", a review).
  const bool kept = w.samples_written() > 0 && rate_mismatch.empty();
  if (kept) staged.keep();  // before "LOG -> OUT" is said: the rename may be refused
  std::printf("%s%s%s: %llu samples from %llu stream frames (%llu frames read%s, %llu other ids)\n", a.log.c_str(),
              kept ? " -> " : "", kept ? a.out.c_str() : "", static_cast<unsigned long long>(w.samples_written()),
              static_cast<unsigned long long>(stream_frames), static_cast<unsigned long long>(frames),
              stream_iface.empty() ? "" : (" on " + stream_iface).c_str(), static_cast<unsigned long long>(other));
  if (elsewhere > 0)
    std::printf("%llu frame(s) on other interfaces: not read\n", static_cast<unsigned long long>(elsewhere));
  std::printf("gaps %llu (%llu samples lost), duplicates %llu\n", static_cast<unsigned long long>(st.gaps),
              static_cast<unsigned long long>(st.lost), static_cast<unsigned long long>(st.duplicates - late_parts));
  if (late > 0)
    std::printf("%llu frame(s) logged more than the reorder window (%u samples) behind the stream: not in the capture "
                "([dut] reorder_window)\n", static_cast<unsigned long long>(late), reasm.window());
  // The rate is the header's, and every time the analysis gives rests on it: said, never guessed.
  std::printf("rate %s Hz (%s)\n", fmt::format("{}", h.rate_hz).c_str(),
              a.rate_hz                                    ? "--rate"
              : sp.key_where.count("rate_hz")              ? sp.key_where.at("rate_hz").c_str()
              : lo.stream || dut.contains("dbc")           ? "the default: [dut.stream] has no rate_hz"
                                                           : "the rig protocol's");
  if (back > 0)
    std::printf("%llu stream frame(s) stamped earlier than a frame before them (the first at %s:%zu, %s s back): the "
                "log's lines are out of order or its clock stepped back; samples are placed by their counter\n",
                static_cast<unsigned long long>(back), a.log.c_str(), back_line, fmt::format("{:.6g}", back_s).c_str());
  if (tail > 0)
    std::printf("%llu incomplete sample(s) at the end (a part without its partner): not in the capture\n",
                static_cast<unsigned long long>(tail));
  for (std::size_t i = 0; i < st.gap_list.size() && i < 20; ++i)
    std::printf("  gap at seq %llu: %llu samples\n", static_cast<unsigned long long>(st.gap_list[i].first),
                static_cast<unsigned long long>(st.gap_list[i].second));
  // The list holds the first kMaxGapList; the count is every gap's.
  if (st.gaps > 20) std::printf("  ... %llu more gaps\n", static_cast<unsigned long long>(st.gaps - 20));
  for (const auto& p : problems) std::fprintf(stderr, "%s\n", p.c_str());
  if (!clock_line.empty()) std::printf("%s\n", clock_line.c_str());
  if (!rate_mismatch.empty()) {
    staged.drop();
    std::fprintf(stderr, "%s\n", rate_mismatch.c_str());
    return kExitUsage;
  }
  if (implausible > 0) {
    // The first not finite named too where it is not the first outside the range.
    const std::string nf = not_finite > 0 && first_not_finite != first_implausible
                               ? "; the first not finite at " + first_not_finite
                               : std::string();
    std::fprintf(stderr, "%llu decoded value(s) outside their signal's DBC range, %llu of them not finite (the first "
                 "at %s%s): the DBC may not describe these frames (check the signal's byte order @0/@1, sign, factor "
                 "and offset), or the DUT went past its DBC's range; the capture holds them as decoded%s\n",
                 static_cast<unsigned long long>(implausible), static_cast<unsigned long long>(not_finite),
                 first_implausible.c_str(), nf.c_str(),
                 not_finite > 0 ? " (a value not finite fails every analysis: exit 2)" : "");
  }
  if (!cut.empty()) {
    if (w.samples_written() == 0)  // nothing before it: no capture, the rest is all there is
      staged.drop();
    else
      staged.keep();
    std::fprintf(stderr, "%s\n%s; import the rest into another capture with --from-line %zu\n", cut.c_str(),
                 w.samples_written() == 0 ? (a.out + " not written: no sample before it").c_str()
                                          : (a.out + " holds the " + std::to_string(w.samples_written()) +
                                             " sample(s) before it").c_str(),
                 cut_line);
    return kExitUsage;
  }
  if (w.samples_written() == 0) {
    // Nothing of the [dut] stream in the log (another DUT's layout, --iface naming no frame, an
    // empty file): an empty capture would only fail later in rig analyze, far from the cause.
    staged.drop();
    // Counted as the summary counts them: the frames read, on the interface read, and those
    // elsewhere apart (all of a log's frames on can0 were "in 5991 frame(s) on can1" under
    // --iface can1, the summary saying 0 read there: a review).
    const std::string on = !a.iface.empty() ? a.iface : stream_iface;
    const std::string rest =
        elsewhere == 0 ? std::string()
                       : " (" + std::to_string(elsewhere) + " on other interfaces, not read" +
                             (a.iface.empty() ? std::string(")") : std::string(": is --iface " + a.iface + " the DUT's?)"));
    std::fprintf(stderr, "%s: no sample of the [dut] stream (%s) in the %llu frame(s) read%s%s; %s not written\n",
                 a.log.c_str(), a.hardware.c_str(), static_cast<unsigned long long>(frames),
                 on.empty() ? "" : (" on " + on).c_str(), rest.c_str(), a.out.c_str());
    return kExitUsage;
  }
  staged.keep();
  if (not_finite > 0) return kExitUsage;
  if (unreadable + malformed > 0) {
    std::fprintf(stderr, "%llu line(s) could not be read, %llu stream frame(s) malformed; the capture holds the rest\n",
                 static_cast<unsigned long long>(unreadable), static_cast<unsigned long long>(malformed));
    return kExitUsage;
  }
  return kExitPass;
}

}  // namespace

void add_capture(CLI::App& app, int& rc) {
  auto* cap = app.add_subcommand("capture", "Capture files from other sources");
  cap->require_subcommand(1);
  auto a = std::make_shared<ImportArgs>();
  auto* imp = cap->add_subcommand("import",
                                  "A candump log (-l / -L files or candump's screen output) into a capture file, "
                                  "through the hardware file's [dut] stream");
  imp->add_option("log", a->log, "candump log")->required();
  imp->add_option("--hardware", a->hardware, "hardware file whose [dut] describes the stream (dbc, [dut.stream])")
      ->required();
  imp->add_option("--out", a->out, "capture file to write")->required();
  imp->add_option("--serial", a->serial, "the DUT's serial number (the header's), 1-32 printable ASCII")->check(serial_validator());
  imp->add_option("--orientation", a->orientation, "U10 or U20 (the header's)")->capture_default_str();
  imp->add_option("--phase", a->phase, "phase name in the header")->capture_default_str();
  // Checked as typed (1e-7 was named 1e-07); the same range as cmd_import's check below.
  imp->add_option("--rate", a->rate_hz, "sample rate in Hz (default: the stream's rate_hz)")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            const std::optional<double> x = finite_number(v);
            if (x && *x >= capture::kMinRateHz && *x <= capture::kMaxRateHz) return {};
            return "'" + shown_ascii(v) + "'" + range_note(v) + ": must be in [" +
                   fmt::format("{}", capture::kMinRateHz) + ", " + fmt::format("{}", capture::kMaxRateHz) + "] Hz";
          },
          ""));
  imp->add_option("--iface", a->iface, "only frames logged on this interface");
  imp->add_option("--from-line", a->from_line, "the log's first line to import (after a DUT restart or a pause)")
      ->check(whole_in("a line number", 1));
  imp->callback([a, &rc] { rc = cmd_import(*a); });
}

}  // namespace rig::cli
