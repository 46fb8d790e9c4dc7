// The emulated plant's table: the rig's real client logic over the emulated
// drive's register map, in this process and in simulated time.
#pragma once
#include <memory>

#include "plant/table/table_emulator.hpp"
#include "rig/modbus/table_client.hpp"

namespace rig::modbus {

// Waits go through `clock` (a SimClock whose advance steps the emulator), so a
// 180° move takes simulated seconds and no wall time.
inline std::unique_ptr<RotaryTable> make_inprocess_table(rig::plant::TableEmulator& emu, Clock& clock) {
  return make_inprocess_table(static_cast<RegisterDevice&>(emu), clock, TableOptions{});
}

}  // namespace rig::modbus
