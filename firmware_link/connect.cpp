#include "firmware_link/connect.hpp"

#include "firmware_link/socketcan.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::link {

namespace {
void check_dut_keys(const toml::table& t) {
  cfg::check_keys(t, {"can", "silence_ms", "command_timeout_ms", "command_attempts", "reorder_window", "rcvbuf_kb",
                      "loop_test", "commands", "dbc", "stream", "design"},
                  "dut");
}
}  // namespace

LinkOptions link_options(const toml::table& t) {
  check_dut_keys(t);
  LinkOptions o;
  o.silence_s = cfg::get_number(t, "silence_ms", 100.0, 5.0, 60000.0) / 1e3;
  o.command_timeout_s = cfg::get_number(t, "command_timeout_ms", 250.0, 1.0, 60000.0) / 1e3;
  o.command_attempts = static_cast<int>(cfg::get_int(t, "command_attempts", 3, 1, 100));
  o.reorder_window = static_cast<uint32_t>(cfg::get_int(t, "reorder_window", 8, 1, 4096));
  o.loop_test = cfg::get_bool(t, "loop_test", true);
  o.commands = cfg::get_bool(t, "commands", true);
  if (t.get("dbc") || t.get("stream")) o.stream = stream_decoder_from_config(t);
  // The reassembly tells late from new only if the window is at most half the counter's period:
  // said here at the file's line, with the key to change (it was the reassembler's bare message,
  // at the first frame, a review).
  if (o.stream && !StreamReassembler::window_fits(o.reorder_window, o.stream->counter_bits())) {
    const toml::node* w = t.get("reorder_window");
    const toml::node* st = t.get("stream");
    const std::string at = w ? cfg::where(*w) + ": [dut] reorder_window" : st ? cfg::where(*st) + ": [dut.stream]" : "[dut]";
    throw ConfigError(at + ": a reorder window of " + std::to_string(o.reorder_window) + " samples is more than half the " +
                      std::to_string(o.stream->counter_bits()) + "-bit counter's period (" +
                      std::to_string(uint64_t{1} << (o.stream->counter_bits() - 1)) + "): set [dut] reorder_window to at most that");
  }
  return o;
}

namespace {
// What [dut] says beyond the link options: the interface and the socket's buffer.
struct DutSocket {
  std::string iface;
  SocketCanOptions so;
};

DutSocket dut_socket(const toml::table& t) {
  DutSocket d;
  d.iface = cfg::get_string(t, "can");
  if (d.iface.empty() || d.iface.size() >= 16) {
    const toml::node* n = t.get("can");
    throw ConfigError(cfg::where(n ? *n : static_cast<const toml::node&>(t)) + ": 'can' = \"" + d.iface +
                      "\" is not a network interface name (1..15 characters)");
  }
  d.so.rcvbuf_bytes = static_cast<int>(cfg::get_int(t, "rcvbuf_kb", 8192, 16, 1 << 20) * 1024);
  return d;
}
}  // namespace

void check_dut_config(const toml::table& t) {
  link_options(t);
  dut_socket(t);
}

std::unique_ptr<CanDutLink> connect_dut(const toml::table& t, Clock& clock) {
  const LinkOptions o = link_options(t);
  const DutSocket d = dut_socket(t);
  return std::make_unique<CanDutLink>(std::make_unique<SocketCanTransport>(d.iface, d.so), clock, o);
}

}  // namespace rig::link
