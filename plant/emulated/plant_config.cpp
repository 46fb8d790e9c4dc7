#include "plant/emulated/plant_config.hpp"

#include "plant/emulated/world.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::plant {

const toml::table& plant_section(const toml::table& profile) {
  static const toml::table none;
  if (const toml::table* t = cfg::get_table(profile, "plant")) return *t;
  return none;
}

double validate_plant_section(const toml::table& plant) {
  // Building it is the check that cannot drift from what the plant reads (cheap: no thread,
  // no I/O, the DUT's loop locks in a fraction of a simulated second).
  EmulatedPlant probe(plant);
  return probe.dut_source().output_rate_hz();
}

}  // namespace rig::plant
