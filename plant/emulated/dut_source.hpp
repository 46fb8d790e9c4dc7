// The emulated DUT's physics as the rest of the plant sees it: one call per
// output period (1 kHz) returns the sample-and-held x(t), y(t) in g.
// Implemented in plant/dut (closed loop + noise); the firmware emulator and the
// direct emulated link both read from it.
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include <toml++/toml.h>

#include "rig/core/dut_link.hpp"

namespace rig::plant {

class DutSource {
 public:
  virtual ~DutSource() = default;
  virtual double output_rate_hz() const = 0;
  // Table angle about the turning axis, degrees (U10 = table.u10_deg, U20 = +180°).
  virtual void set_table_angle_deg(double deg) = 0;
  // Advance one output period; x = unfiltered, y = through the output filter (g).
  virtual void next(float& x_g, float& y_g) = 0;
  virtual void set_filter(const FilterConfig& f) = 0;
  virtual FilterConfig filter() const = 0;
  virtual double temperature_c() const = 0;
  virtual std::string serial() const = 0;
};

// Builds the emulated DUT. `dut_cfg` is the [plant.dut] table of the profile
// (overrides on the default DUT profile), may be null. Same seed => bit-identical output.
std::unique_ptr<DutSource> make_dut_source(const toml::table* dut_cfg, uint64_t seed);

}  // namespace rig::plant
