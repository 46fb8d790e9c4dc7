// `rig dut`: a technician's manual control of a DUT over CAN
// (docs/can-protocol.md): info, stream, output filter, the loop test, and
// decoding a candump log with the protocol's DBC.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "design/filter.hpp"
#include "firmware_link/candump_log.hpp"
#include "firmware_link/connect.hpp"
#include "firmware_link/dbc.hpp"
#include "firmware_link/dbc_stream.hpp"
#include "firmware_link/protocol.hpp"
#include "app/commands.hpp"
#include "app/hardware_file.hpp"
#include "app/number_option.hpp"
#include "app/output_file.hpp"
#include "procedures/acceptance/loop_phase.hpp"
#include "rig/core/clock.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/executive/signals.hpp"

namespace rig::cli {

namespace {

struct DutArgs {
  std::string can, hardware;
  // stream: 0 = no limit (the option not given; a given one is checked to be > 0)
  double seconds = 0;
  std::uint64_t count = 0;
  std::string out;
  bool quiet = false;
  // set-filter
  std::vector<std::string> biquads;
  bool paper = false;
  double rate_hz = 10000.0;
  bool off = false;
  // loop-test
  LoopTestRequest loop;
  int record_ms = 100;
  // decode
  std::string log, dbc;  // empty: the rig protocol's DBC built into the program
  bool summary = false;
};

// [dut] from --hardware FILE, with --can overriding the interface.
toml::table dut_config(const DutArgs& a) {
  toml::table t;
  if (!a.hardware.empty()) t = load_hardware_section(a.hardware, "dut");  // moved: keeps file:line and dbc's folder
  if (!a.can.empty()) t.insert_or_assign("can", a.can);
  if (!t.contains("can")) throw ConfigError("rig dut: give --can IFACE (or --hardware FILE with a [dut] can = ...)");
  return t;
}

// [dut] for an action that needs the DUT's command channel: refused as configuration, before
// the socket opens, when the hardware file says the DUT has none.
toml::table command_dut_config(const DutArgs& a, const char* action) {
  toml::table t = dut_config(a);
  if (!link::link_options(t).commands)
    throw ConfigError(a.hardware + ": [dut] commands = false: the DUT has no command channel, and `rig dut " + action +
                      "` needs one (`rig dut stream` reads a DUT without commands)");
  return t;
}

void print_filter(const FilterConfig& f) {
  std::printf("filter:      %s, %zu section(s) at %.0f Hz\n", f.enabled ? "on" : "off", f.sections.size(), f.rate_hz);
  for (std::size_t i = 0; i < f.sections.size(); ++i) {
    const Biquad& b = f.sections[i];
    std::printf("  section %zu: b = [%.9g, %.9g, %.9g]  a = [1, %.9g, %.9g]\n", i, b.b0, b.b1, b.b2, b.a1, b.a2);
  }
}

int cmd_info(const DutArgs& a) {
  RealClock clock;
  auto link = link::connect_dut(command_dut_config(a, "info"), clock);
  const CancelToken never;
  const DutInfo i = link->info(never);
  std::printf("link:        %s\n", link->describe().c_str());
  std::printf("serial:      %s\nfirmware:    %s\ntemperature: %.2f degC\noutput rate: %.0f Hz\n", i.serial.c_str(),
              i.firmware.c_str(), i.temperature_c, i.output_rate_hz);
  print_filter(link->get_filter(never));
  if (const auto hb = link->last_heartbeat())
    std::printf("heartbeat:   #%u, %s, last sample %u\n", hb->counter,
                (hb->state & link::hb_state::kStreaming) ? "streaming" : "idle", hb->last_seq);
  return kExitPass;
}

// The samples to stream: --count, else --seconds at 1 kHz, else -1 (until Ctrl-C). Their
// ranges are checked by the options (a count >= 1, seconds finite and > 0): a negative or NaN
// limit here meant "stream forever" (a review).
long stream_limit(const DutArgs& a) {
  if (a.count > 0) return static_cast<long>(std::min<std::uint64_t>(a.count, std::numeric_limits<long>::max()));
  if (a.seconds > 0) return std::max(1L, std::lround(a.seconds * 1000.0));
  return -1;
}

int cmd_stream(const DutArgs& a) {
  // Where the samples go is checked before the link opens (a folder, a missing folder: exit 2,
  // not the socket's 4); the file is opened once the DUT answers, so a dead link leaves an
  // earlier file as it was.
  if (!a.out.empty()) check_output_file(a.out, "rig dut stream --out");
  CancelSource cancel;
  SignalWatcher signals(cancel);  // Ctrl-C ends the stream cleanly
  RealClock clock;
  auto link = link::connect_dut(dut_config(a), clock);
  std::ofstream file;
  std::ostream* os = &std::cout;
  if (!a.out.empty()) {
    file.open(a.out);
    if (!file) throw ConfigError("rig dut stream --out " + a.out + ": cannot open for writing: " + std::strerror(errno));
    os = &file;
  }
  const long want = stream_limit(a);
  *os << "# seq x_g y_g status   (" << link->describe() << ")\n";
  link->start_stream(cancel.token());
  std::vector<Sample> buf(100);
  long got = 0;
  int rc = kExitPass;
  try {
    while (want < 0 || got < want) {
      const std::size_t n = want < 0 ? buf.size() : std::min<std::size_t>(buf.size(), static_cast<std::size_t>(want - got));
      link->read(std::span(buf.data(), n), cancel.token());
      if (!a.quiet)
        for (std::size_t i = 0; i < n; ++i) {
          char line[96];
          std::snprintf(line, sizeof line, "%u %.9g %.9g 0x%03X\n", buf[i].seq, static_cast<double>(buf[i].x_g),
                        static_cast<double>(buf[i].y_g), buf[i].status);
          *os << line;
        }
      got += static_cast<long>(n);
    }
  } catch (const AbortedError&) {
    rc = kExitAborted;
  }
  link->stop_stream();
  os->flush();
  const LinkStats s = link->stats();
  std::fprintf(stderr, "rig dut stream: %ld samples, %llu gaps (%llu lost), %llu duplicates/late\n", got,
               static_cast<unsigned long long>(s.gaps), static_cast<unsigned long long>(s.lost),
               static_cast<unsigned long long>(s.duplicates));
  for (std::size_t i = 0; i < s.gap_list.size() && i < 20; ++i)
    std::fprintf(stderr, "  gap at seq %llu: %llu sample(s)\n", static_cast<unsigned long long>(s.gap_list[i].first),
                 static_cast<unsigned long long>(s.gap_list[i].second));
  return rc;
}

// Each coefficient decimal text, as every number on the command line (from_chars: "0x1" and
// "0x1p3", which std::stod read as hexadecimal, are not; a technician's re-test), blanks around it
// and a leading '+' allowed.
// The checks hold the section as sent, in IEEE binary32 (docs/can-protocol.md): 1e-50 is 0
// there and 0.99999999 is 1 (a pole on the unit circle), both passed as doubles (reviews).
Biquad parse_biquad(const std::string& text) {
  std::vector<double> v;
  for (std::size_t from = 0;;) {  // every item, an empty last one included ("1,0,0,0,0,")
    const std::size_t comma = std::min(text.find(',', from), text.size());
    const std::string item = text.substr(from, comma - from);
    std::string_view num = item;
    num.remove_prefix(std::min(num.find_first_not_of(" \t"), num.size()));
    num.remove_suffix(num.size() - std::min(num.find_last_not_of(" \t") + 1, num.size()));
    if (num.size() > 1 && num[0] == '+' && num[1] != '-') num.remove_prefix(1);
    double x = 0;
    const auto [end, ec] = std::from_chars(num.data(), num.data() + num.size(), x);
    if (num.empty() || ec == std::errc::invalid_argument || end != num.data() + num.size())
      throw ConfigError("--biquad '" + text + "': '" + item + "' is not a decimal number");
    // Nan was called "unstable" (a review); 1e-400 (out of a double's range toward 0) was "not finite".
    const bool toward_zero = ec == std::errc::result_out_of_range && num.find_first_of("123456789") != std::string_view::npos &&
                             (num.find("e-") != std::string_view::npos || num.find("E-") != std::string_view::npos);
    if (ec == std::errc::result_out_of_range && !toward_zero) x = std::numeric_limits<double>::infinity();
    if (!(std::abs(x) <= std::numeric_limits<float>::max()))
      throw ConfigError("--biquad '" + text + "': '" + item + "' is not a finite number within the protocol's 32-bit float range");
    if (toward_zero || (x != 0 && static_cast<float>(x) == 0))
      throw ConfigError("--biquad '" + text + "': '" + item +
                        "' is 0 in the protocol's 32-bit float (nearer 0 than 1.4e-45): give 0, or a coefficient it holds");
    v.push_back(static_cast<float>(x));
    if (comma == text.size()) break;
    from = comma + 1;
  }
  if (v.size() != 5) throw ConfigError("--biquad '" + text + "': give 5 numbers b0,b1,b2,a1,a2 (a0 = 1)");
  const Biquad b{v[0], v[1], v[2], v[3], v[4]};
  if (b.b0 == 0 && b.b1 == 0 && b.b2 == 0)  // its output is 0 whatever the input
    throw ConfigError("--biquad '" + text + "': b0, b1 and b2 are all 0: the section passes nothing");
  if (!stable_section(b))  // before the DUT is asked: its firmware refuses it only at commit
    throw ConfigError("--biquad '" + text + "': unstable: its poles (a1, a2), as the protocol's 32-bit float holds them, are not inside the unit circle");
  return b;
}

// The paper's W_f(z) as one --biquad value, each coefficient in the shortest text that reads back to it.
std::string paper_section_text() {
  const Biquad b = design::paper_wf().sections.front();
  return fmt::format("{},{},{},{},{}", b.b0, b.b1, b.b2, b.a1, b.a2);
}

int cmd_set_filter(const DutArgs& a) {
  FilterConfig f;
  f.rate_hz = a.rate_hz;
  f.enabled = !a.off;
  // One or the other (the synopsis's `--paper | --biquad`): both loaded the paper's section with
  // the given ones chained after it, a filter that is neither (a technician's review).
  if (a.paper && !a.biquads.empty())
    throw ConfigError("rig dut set-filter: give --paper or --biquad, not both (--paper loads the paper's filter alone; "
                      "its section is b0,b1,b2,a1,a2 = " + paper_section_text() + " for a --biquad cascade)");
  if (a.paper) f.sections = design::paper_wf().sections;  // docs/method.md, W_f(z)
  // As many as the protocol carries, said before the link opens (it was said by the link, or hidden
  // behind a link that could not open: a technician's re-test).
  if (a.biquads.size() > static_cast<std::size_t>(link::kMaxSections))
    throw ConfigError(fmt::format("rig dut set-filter: {} --biquad sections; the DUT takes at most {}", a.biquads.size(),
                                  link::kMaxSections));
  for (const auto& b : a.biquads) f.sections.push_back(parse_biquad(b));
  if (f.sections.empty()) throw ConfigError("rig dut set-filter: give --paper or at least one --biquad b0,b1,b2,a1,a2");
  RealClock clock;
  auto link = link::connect_dut(command_dut_config(a, "set-filter"), clock);
  const CancelToken never;
  link->set_filter(f, never);
  print_filter(link->get_filter(never));
  return kExitPass;
}

int cmd_filter_enable(const DutArgs& a, bool on) {
  RealClock clock;
  auto link = link::connect_dut(command_dut_config(a, on ? "filter-on" : "filter-off"), clock);
  link->set_filter_enabled(on, CancelToken{});
  std::printf("filter: %s\n", on ? "on" : "off");
  return kExitPass;
}

// A decoded value as text that keeps its digits: an integer signal with whole-number factor and
// offset exactly, from its raw integer (dbc_physical_exact: a double read 2^53 + 1 as 2^53, and a
// raw 2^53 + 1 with offset -2 as ...990, a review); another integer signal (raw * factor + offset)
// to 15 significant digits, every one a double holds faithfully, a whole number below 2^53
// exactly; a float32 or float64 signal in the shortest text that reads back to it.
// "%.9g" cut 12038801.95 to 12038802 and 1000000001 to 1e+09 (a review).
std::string physical_text(const link::DecodedSignal& s, const link::DbcSignal* sd) {
  const double v = s.value;
  const int value_type = sd ? sd->value_type : 0;
  // A float32 as it came (factor 1, offset 0) in a float's shortest text; scaled, the double the
  // scaling made (1.0f with offset 1e-10 printed 1, 3e38f times 1e10 inf: a re-test).
  if (value_type == 1 && sd->factor == 1 && sd->offset == 0) return fmt::format("{}", static_cast<float>(v));
  if (value_type == 1) return fmt::format("{}", v);
  if (sd)
    if (std::string exact = link::dbc_physical_exact(*sd, s.raw); !exact.empty()) return exact;
  if (value_type == 2 || !std::isfinite(v)) return fmt::format("{}", v);
  if (v == std::trunc(v) && std::fabs(v) < 9007199254740992.0) return fmt::format("{:.0f}", v);
  return fmt::format("{:.15g}", v);
}

// A frame's time as decoded lines show it: "-" for a line that had none (candump's screen output
// without -t), where 0.000000 read as a real time (a bring-up review).
std::string time_text(const link::LoggedFrame& lf) { return lf.timed ? fmt::format("{:.6f}", lf.t_s) : "-"; }

// Decodes every frame it can; a line it cannot read (not a frame, CAN FD, truncated) or a
// frame of a protocol message it cannot decode (too short for its DLC) is skipped, counted
// and named LOG:LINE on stderr. Exit 0: every line decoded; 2: some line was skipped or the
// log holds no frame at all (the decodable rest is still printed).
int cmd_decode(const DutArgs& a) {
  // A folder opens and reads as empty: it said "holds no CAN frame" (a review).
  if (struct stat st{}; ::stat(a.log.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
    throw ConfigError(a.log + ": is a folder, not a candump log (give one file)");
  // The DBC: --dbc FILE; else the hardware file's [dut], checked as `rig run` checks it (its
  // dbc found beside the file); else the rig protocol's, built in.
  std::shared_ptr<const link::Dbc> db;
  std::string dbc_name;
  if (!a.dbc.empty()) {
    db = std::make_shared<const link::Dbc>(link::Dbc::parse_file(a.dbc));
    dbc_name = a.dbc;
  } else if (!a.hardware.empty()) {
    const toml::table t = load_hardware_section(a.hardware, "dut");
    if (const auto layout = link::link_options(t).stream) {
      db = std::shared_ptr<const link::Dbc>(layout, &layout->dbc());  // kept alive by its layout
      dbc_name = link::dut_dbc_path(t);
    }
  }
  if (!db) {
    db = link::rig_protocol_dbc();
    dbc_name = "docs/rig-dut.dbc, built in";
  }
  const link::Dbc& dbc = *db;
  std::ifstream in(a.log);
  if (!in) throw ConfigError(a.log + ": cannot open candump log");
  constexpr unsigned long kNamedSkips = 20;  // then only counted: a wrong file must not flood the terminal
  std::map<std::string, unsigned long> per;
  // Every frame is counted once in the summary (its messages, error frames, other ids, or not
  // decoded); a skipped line is one that holds no frame (a short frame was counted as a frame and
  // a skipped line, and the parts did not add up: a technician's re-test).
  unsigned long frames = 0, foreign = 0, errors = 0, undecoded = 0, skipped = 0, named = 0;
  auto skip = [&](std::size_t line, const std::string& why, const char* what = "skipped") {
    if (++named <= kNamedSkips) std::fprintf(stderr, "%s:%zu: %s: %s\n", a.log.c_str(), line, what, why.c_str());
  };
  link::CandumpLogReader reader(in);
  link::CandumpLogReader::Entry e;
  while (reader.next(e)) {
    if (e.parsed.kind != link::LogLineKind::Frame) {
      ++skipped;
      skip(e.line, e.parsed.problem);
      continue;
    }
    const link::LoggedFrame& lf = e.parsed.frame;
    ++frames;
    if (lf.frame.error) {
      ++errors;
      if (!a.summary) std::printf("%s %s error frame: %s\n", time_text(lf).c_str(), lf.iface.c_str(),
                                  link::classify_error_frame(lf.frame).text.c_str());
      continue;
    }
    // A remote request carries no data: its message's name, no values (they read as zeros).
    if (lf.any.rtr) {
      if (const link::DbcMessage* m = dbc.find(lf.any.id, lf.any.extended)) {
        ++per[m->name + " remote request"];
        if (!a.summary) std::printf("%s %s %s remote request\n", time_text(lf).c_str(), lf.iface.c_str(), m->name.c_str());
      } else {
        ++foreign;
      }
      continue;
    }
    std::string err;
    const auto sig = dbc.decode(lf.any, &err);  // classic or CAN FD as logged
    if (!sig) {
      if (err.empty()) ++foreign;  // an id the DBC does not describe: counted, not an error
      else ++undecoded, skip(e.line, err + " (" + dbc_name + ")", "not decoded");
      continue;
    }
    const link::DbcMessage& msg = *dbc.find(lf.any.id, lf.any.extended);
    const std::string& name = msg.name;
    ++per[name];
    if (a.summary) continue;
    std::printf("%s %s %s", time_text(lf).c_str(), lf.iface.c_str(), name.c_str());
    for (const auto& s : *sig) {
      const link::DbcSignal* sd = msg.signal(s.name);
      const std::string v = physical_text(s, sd);
      if (s.value_name.empty()) std::printf(" %s=%s%s%s", s.name.c_str(), v.c_str(), s.unit.empty() ? "" : " ", s.unit.c_str());
      else std::printf(" %s=\"%s\" (%s)", s.name.c_str(), s.value_name.c_str(), v.c_str());
    }
    std::printf("\n");
  }
  if (named > kNamedSkips)
    std::fprintf(stderr, "%s: ... and %lu more line(s) skipped or not decoded\n", a.log.c_str(), named - kNamedSkips);
  std::printf("%s: %lu frames: ", a.log.c_str(), frames);
  for (const auto& [k, n] : per) std::printf("%s %lu, ", k.c_str(), n);
  std::printf("error frames %lu, other ids %lu, not decoded %lu; skipped lines %lu\n", errors, foreign, undecoded, skipped);
  if (frames == 0 && skipped == 0) {
    std::fprintf(stderr, "rig: %s holds no CAN frame\n", a.log.c_str());
    return kExitUsage;
  }
  // Frames, and not one of them a message of the DBC: the wrong DBC or the wrong log, not a
  // decoded log (it was exit 0, a review).
  if (per.empty() && foreign > 0 && undecoded == 0) {
    std::fprintf(stderr, "rig: none of the %lu frame(s) in %s is a message of %s\n", frames, a.log.c_str(),
                 dbc_name.c_str());
    return kExitUsage;
  }
  return skipped || undecoded ? kExitUsage : kExitPass;
}
// The loop test at the bench: the same request, analysis and record file as `rig run`'s loop phase.
int cmd_loop_test(DutArgs a) {
  CancelSource cancel;
  SignalWatcher signals(cancel);
  a.loop.record_s = a.record_ms / 1e3;
  // Where the records go is checked before the DUT is asked: a measurement is never made only to
  // be lost to a path that cannot be written.
  if (!a.out.empty()) check_writable_file(a.out, "rig dut loop-test --out");
  RealClock clock;
  auto link = link::connect_dut(command_dut_config(a, "loop-test"), clock);
  const LoopTestResponse r = link->loop_test(a.loop, cancel.token());
  if (!r.supported) {
    std::printf("loop test: not supported: %s\n", r.reason.c_str());
    return kExitHardware;
  }
  if (!a.out.empty()) write_file_atomic(a.out, acceptance::loop_test_csv(r));  // replaced, never written through
  const nlohmann::json fig = acceptance::loop_test_figures(r);
  for (std::size_t k = 0; k < fig["per_step"].size(); ++k) {
    const auto& s = fig["per_step"][k];
    std::printf("step %zu: settling %.2f ms, bandwidth (0.5) %.1f Hz, final %.5f, overshoot %.1f %%%s\n", k + 1,
                s["settling_time_s"].get<double>() * 1e3, s["bandwidth_0p5_hz"].get<double>(),
                s["final_value"].get<double>(), s["overshoot"].get<double>() * 100,
                s["saturated"].get<bool>() ? ", SATURATED" : "");
  }
  // One step has no interval (loop_test_figures): its figures are printed alone.
  auto interval = [&fig](const char* key, double scale, const char* format) {
    const auto& iv = fig[key];
    return iv.is_null() ? std::string() : fmt::format(fmt::runtime(format), iv[0].get<double>() * scale, iv[1].get<double>() * scale);
  };
  std::printf("settling time (5 %% band): %.3f ms%s\nbandwidth (0.5 level):    %.1f Hz%s\n",
              fig["settling_time_s"].get<double>() * 1e3, interval("settling_time_interval_s", 1e3, " [{:.3f}, {:.3f}]").c_str(),
              fig["bandwidth_0p5_hz"].get<double>(), interval("bandwidth_0p5_interval_hz", 1, " [{:.1f}, {:.1f}]").c_str());
  if (r.steps.size() >= 2)
    std::printf("(%zu steps of %g g at %g Hz; 95 %% intervals over the steps)\n", r.steps.size(), r.amplitude_g, r.rate_hz);
  else
    std::printf("(1 step of %g g at %g Hz: no interval, its repeatability is not measured)\n", r.amplitude_g, r.rate_hz);
  return kExitPass;
}

void add_link_options(CLI::App* c, DutArgs& a) {
  c->add_option("--can", a.can, "CAN interface of the DUT (e.g. can0, vcan0)");
  c->add_option("--hardware", a.hardware, "Take [dut] (interface, timeouts) from this hardware file");
}

}  // namespace

void add_dut(CLI::App& app, int& rc) {
  auto* dut = app.add_subcommand("dut", "Manual control of a DUT over CAN (info, stream, output filter, log decode)");
  dut->require_subcommand(1);
  auto a = std::make_shared<DutArgs>();
  // The link options may come before or after the action, as the README's synopsis writes them
  // (`rig dut --can can0 info`) and as people type them (`rig dut info --can can0`).
  add_link_options(dut, *a);

  auto* info = dut->add_subcommand("info", "Serial number, firmware version, temperature and output filter");
  add_link_options(info, *a);
  info->callback([a, &rc] { rc = cmd_info(*a); });

  auto* stream = dut->add_subcommand("stream", "Stream samples (seq x_g y_g status per line) until Ctrl-C or a limit");
  add_link_options(stream, *a);
  // Checked before the link opens: a bad limit is exit 2 whether or not the interface exists.
  stream->add_option("--seconds", a->seconds, "Stop after this many seconds of samples (1 kHz), in (0, 1e6]")
      ->check(number_in(0, 1e6, true, "a number of seconds"));
  stream->add_option("--count", a->count, "Stop after this many samples, >= 1")
      ->check(whole_in("a number of samples", 1));
  stream->add_option("--out", a->out, "Write the samples to this file instead of stdout (not a folder)");
  stream->add_flag("--quiet", a->quiet, "Only the summary (gaps, duplicates)");
  stream->callback([a, &rc] { rc = cmd_stream(*a); });

  auto* setf = dut->add_subcommand("set-filter", "Load output-filter coefficients into the DUT (biquad cascade)");
  add_link_options(setf, *a);
  setf->add_option("--biquad", a->biquads, "One section b0,b1,b2,a1,a2 (repeat for a cascade)");
  setf->add_flag("--paper", a->paper, "The paper's MCU filter 0.148895 z^2/(z^2 - 1.228261 z + 0.377156)");
  // Checked on the text before the link opens (a review: --rate 0 and nan were exit 4, "CAN
  // interface ..."); the range a profile's [filter] rate_hz takes.
  setf->add_option("--rate", a->rate_hz, "Rate the filter runs at inside the DUT, Hz")
      ->capture_default_str()
      ->check(number_in(1.0, 1e7, false, "a rate in Hz"));
  setf->add_flag("--off", a->off, "Load it but leave the filter switched off");
  setf->callback([a, &rc] { rc = cmd_set_filter(*a); });

  auto* on = dut->add_subcommand("filter-on", "Switch the DUT's output filter on");
  add_link_options(on, *a);
  on->callback([a, &rc] { rc = cmd_filter_enable(*a, true); });
  auto* off = dut->add_subcommand("filter-off", "Switch the DUT's output filter off");
  add_link_options(off, *a);
  off->callback([a, &rc] { rc = cmd_filter_enable(*a, false); });

  auto* lt = dut->add_subcommand("loop-test", "Run the DUT's loop test: settling time and 0.5-level bandwidth measured");
  add_link_options(lt, *a);
  lt->add_option("--steps", a->loop.steps, "Steps of test torque")->capture_default_str()->check(CLI::Range(1, 100));
  // The protocol's |A| <= 5 g and not 0 (a profile's [loop] amplitude_g alike), checked on the
  // text: CLI::Range let nan and 0 through to the link (exit 4; a review).
  lt->add_option("--amplitude", a->loop.amplitude_g, "Step amplitude, g of input acceleration (not 0)")
      ->capture_default_str()
      ->check(number_in(-5.0, 5.0, false, "a number of g") &
              CLI::Validator([](std::string& v) { return finite_number(v) == 0.0 ? "'" + shown_ascii(v) + "': must not be 0" : std::string(); }, ""));
  lt->add_option("--record-ms", a->record_ms, "Record per step at the loop rate, ms")->capture_default_str()->check(CLI::Range(10, 200));
  lt->add_option("--out", a->out, "Write the raw records (loop-test.csv format) to this file");
  lt->callback([a, &rc] { rc = cmd_loop_test(*a); });

  auto* dec = dut->add_subcommand("decode", "Decode a candump log (candump -l / -L files or candump's screen output) with the protocol's DBC; "
                                     "exit 2 when a line had to be skipped or a frame of the DBC could not be decoded");
  dec->add_option("LOG", a->log, "candump log file")->required();
  dec->add_option("--dbc", a->dbc, "DBC file (default: --hardware FILE's [dut] dbc, else the rig protocol's, "
                                   "docs/rig-dut.dbc, built into the program)");
  dec->add_flag("--summary", a->summary, "Only count the messages");
  dec->callback([a, &rc] { rc = cmd_decode(*a); });
  for (CLI::App* action : dut->get_subcommands({})) action->fallthrough();
}

}  // namespace rig::cli
