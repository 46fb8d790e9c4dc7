#include "plant/emulated/plant_config.hpp"

#include "firmware_link/protocol.hpp"
#include "plant/emulated/world.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::plant {

const toml::table& plant_section(const toml::table& profile) {
  static const toml::table none;
  if (const toml::table* t = cfg::get_table(profile, "plant")) return *t;
  return none;
}

double validate_plant_section(const toml::table& plant) {
  // The serial the emulated DUT reports goes where --serial's goes (passport, history, folder
  // name): held to the same rule at its line (a review: a bell and a newline in it ran PASS, and
  // `rig report` then refused the passport; 60 characters were cut to 32 without a word).
  if (const toml::table* dut = cfg::get_table(plant, "dut"))
    if (const toml::node* n = dut->get("serial"))
      if (const auto s = n->value<std::string>())
        if (const std::string why = link::serial_problem(*s); !why.empty()) cfg::reject(*n, "serial", why);
  // Building it is the check that cannot drift from what the plant reads (cheap: no thread,
  // no I/O, the DUT's loop locks in a fraction of a simulated second).
  EmulatedPlant probe(plant);
  return probe.dut_source().output_rate_hz();
}

}  // namespace rig::plant
