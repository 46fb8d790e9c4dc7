#include "plant/firmware/firmware_config.hpp"

#include "firmware_link/dbc_stream.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::plant {

FirmwareOptions firmware_options(const toml::table* t) {
  FirmwareOptions o;
  if (!t) return o;
  cfg::check_keys(*t, {"commands", "loop_test", "dbc", "stream"}, "plant.firmware");
  o.commands = cfg::get_bool(*t, "commands", true);
  o.loop_test = cfg::get_bool(*t, "loop_test", true);
  // The same reader as the hardware file's [dut] dbc + [dut.stream]: one spelling of a layout.
  if (t->get("dbc") || t->get("stream"))
    o.stream = std::make_shared<const link::DbcStreamEncoder>(link::stream_decoder_from_config(*t, "plant.firmware"));
  return o;
}

}  // namespace rig::plant
