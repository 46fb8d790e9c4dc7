// The profile's [plant.firmware] table: how the emulated DUT's firmware behaves on the bus
// (docs/profiles.md). Read by the in-process plant and by `rig plant serve`, so the same profile
// gives the same firmware in both.
#pragma once
#include <toml++/toml.h>

#include "plant/firmware/firmware_emulator.hpp"

namespace rig::plant {

// [plant.firmware] keys: commands = true (false: no command channel, streams from power-on),
// loop_test = true (false: LOOP_TEST answers UNKNOWN_OP), dbc = "FILE" (relative to the profile)
// with a [plant.firmware.stream] table, spelled as the hardware file's [dut.stream]: the stream's
// layout (default: the rig protocol). Null table: the defaults. Unknown keys
// and bad values => ConfigError naming file:line.
FirmwareOptions firmware_options(const toml::table* firmware);

}  // namespace rig::plant
