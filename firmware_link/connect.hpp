// Factories the rig calls: the DUT link of a hardware file's [dut] table.
#pragma once
#include <memory>

#include <toml++/toml.h>

#include "firmware_link/can_dut_link.hpp"
#include "rig/core/clock.hpp"
#include "rig/core/dut_link.hpp"

namespace rig::link {

// [dut] keys: can = "can0" (required), silence_ms = 100, command_timeout_ms = 250,
// command_attempts = 3, reorder_window = 8, rcvbuf_kb = 8192, loop_test = true, commands = true
// (false: a DUT without a command channel, streaming from power-on), dbc = "FILE" with a
// [dut.stream] table (firmware_link/dbc_stream.hpp; absent: the rig protocol). Unknown keys and
// bad values => ConfigError naming file:line; an interface that cannot be
// opened => HardwareError.
LinkOptions link_options(const toml::table& dut_cfg);
// Every [dut] key checked (link_options and the interface name, the socket buffer), no socket
// opened: the hardware file's validation (app/hardware_file.cpp).
void check_dut_config(const toml::table& dut_cfg);
std::unique_ptr<CanDutLink> connect_dut(const toml::table& dut_cfg, Clock& clock);

}  // namespace rig::link
