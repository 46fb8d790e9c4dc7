// `rig capture import LOG --hardware FILE --out CAPTURE`: a candump log (can-utils
// `candump -l` files, `candump -L` output) turned into the rig's capture file through
// the hardware file's [dut] stream description (its DBC and [dut.stream], or the rig
// protocol), with the reassembly's report: gaps located, duplicates, lines that could not
// be read. `rig analyze CAPTURE --input capture` and the report then work on logs
// recorded by can-utils or any tool writing that format.
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

#include "app/commands.hpp"
#include "app/hardware_file.hpp"
#include "app/output_file.hpp"
#include "app/serial_option.hpp"
#include "firmware_link/candump_log.hpp"
#include "firmware_link/connect.hpp"
#include "firmware_link/dbc.hpp"
#include "firmware_link/dbc_stream.hpp"
#include "rig/capture/capture.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::cli {

namespace {

struct ImportArgs {
  std::string log, hardware, out, serial, orientation = "U10", phase = "import", iface;
  std::optional<double> rate_hz;  // none: the stream's (rate_hz of [dut.stream], 1000 for the rig protocol)
};

// A log's absolute time (seconds since the epoch) as ISO 8601 UTC; "" for relative times.
std::string iso8601(double t_s) {
  if (!(t_s > 1e8)) return {};  // candump -td / -tz style relative stamps
  const std::time_t t = static_cast<std::time_t>(std::floor(t_s));
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[40];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

int cmd_import(const ImportArgs& a) {
  if (a.orientation != "U10" && a.orientation != "U20")
    throw ConfigError("rig capture import: --orientation must be U10 or U20, got '" + a.orientation + "'");
  // The header's rate is checked as every reader of a capture checks it (capture.hpp).
  if (a.rate_hz && !(*a.rate_hz > 0 && *a.rate_hz <= capture::kMaxRateHz))
    throw ConfigError("rig capture import: --rate " + fmt::format("{}", *a.rate_hz) + ": must be in (0, " +
                      fmt::format("{}", capture::kMaxRateHz) + "] Hz");
  check_new_file(a.out, "rig capture import: --out");
  const toml::table hw = load_hardware_file(a.hardware, {"dut"});
  const toml::table& dut = *cfg::get_table(hw, "dut", true);
  const link::LinkOptions lo = link::link_options(dut);  // validates [dut], reads its stream
  const auto decoder = lo.stream ? lo.stream : link::stream_decoder_from_config(dut);
  link::StreamReassembler reasm = decoder->make_reassembler(lo.reorder_window);

  std::ifstream in(a.log);
  if (!in) throw ConfigError(a.log + ": cannot open candump log");

  capture::Header h;
  h.serial = a.serial;
  h.phase = a.phase;
  h.orientation = a.orientation;
  h.rate_hz = a.rate_hz ? *a.rate_hz : decoder->rate_hz();
  // The header is written first; its start time comes from the log's first frame, so the
  // log is read once to find it (cheap next to decoding).
  {
    std::string line;
    while (std::getline(in, line))
      if (const auto lf = link::parse_candump_line(line); lf && (a.iface.empty() || lf->iface == a.iface)) {
        h.started = iso8601(lf->t_s);
        break;
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
  capture::Writer w(a.out, h);

  uint64_t frames = 0, stream_frames = 0, other = 0, unreadable = 0, malformed = 0;
  std::vector<std::string> problems;  // LOG:LINE: why, the first 20
  auto note = [&](std::size_t ln, const std::string& why) {
    if (problems.size() < 20) problems.push_back(a.log + ":" + std::to_string(ln) + ": " + why);
  };
  std::vector<link::StreamPart> parts;
  std::vector<Sample> buf(4096);
  auto drain = [&] {
    while (std::size_t n = reasm.pop(buf)) w.append(std::span<const Sample>(buf.data(), n));
  };
  std::string line;
  for (std::size_t ln = 1; std::getline(in, line); ++ln) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const auto lf = link::parse_candump_line(line);
    if (!lf) {
      ++unreadable;
      note(ln, "not a candump frame line");
      continue;
    }
    if (!a.iface.empty() && lf->iface != a.iface) continue;
    ++frames;
    parts.clear();
    std::string err;
    if (!decoder->decode(lf->any, parts, &err)) {  // classic or CAN FD frames as logged
      ++other;  // commands, heartbeats, other nodes' traffic
      continue;
    }
    if (!err.empty()) {
      ++malformed;
      note(ln, err);
      continue;
    }
    ++stream_frames;
    for (const auto& p : parts) reasm.push_part(p);
    drain();
  }
  reasm.flush();
  drain();
  const LinkStats& st = reasm.stats();
  w.close();

  std::printf("%s -> %s: %llu samples from %llu stream frames (%llu frames read, %llu other ids)\n", a.log.c_str(),
              a.out.c_str(), static_cast<unsigned long long>(w.samples_written()),
              static_cast<unsigned long long>(stream_frames), static_cast<unsigned long long>(frames),
              static_cast<unsigned long long>(other));
  std::printf("gaps %llu (%llu samples lost), duplicates %llu\n", static_cast<unsigned long long>(st.gaps),
              static_cast<unsigned long long>(st.lost), static_cast<unsigned long long>(st.duplicates));
  for (std::size_t i = 0; i < st.gap_list.size() && i < 20; ++i)
    std::printf("  gap at seq %llu: %llu samples\n", static_cast<unsigned long long>(st.gap_list[i].first),
                static_cast<unsigned long long>(st.gap_list[i].second));
  if (st.gap_list.size() > 20) std::printf("  ... %zu more gaps\n", st.gap_list.size() - 20);
  for (const auto& p : problems) std::fprintf(stderr, "%s\n", p.c_str());
  if (w.samples_written() == 0) {
    // Nothing of the [dut] stream in the log (another DUT's layout, --iface naming no frame, an
    // empty file): an empty capture would only fail later in rig analyze, far from the cause.
    std::error_code ec;
    std::filesystem::remove(a.out, ec);
    std::fprintf(stderr, "%s: no sample of the [dut] stream (%s) in %llu frame(s)%s; %s not written\n", a.log.c_str(),
                 a.hardware.c_str(), static_cast<unsigned long long>(frames),
                 a.iface.empty() ? "" : (" on " + a.iface).c_str(), a.out.c_str());
    return kExitUsage;
  }
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
  imp->add_option("--rate", a->rate_hz, "sample rate in Hz (default: the stream's rate_hz)");
  imp->add_option("--iface", a->iface, "only frames logged on this interface");
  imp->callback([a, &rc] { rc = cmd_import(*a); });
}

}  // namespace rig::cli
