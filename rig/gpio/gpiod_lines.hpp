// Real GPIO lines with libgpiod 1.6 (C++ bindings), found by NAME from the
// rig's [gpio] configuration, and the factory the rig calls.
#pragma once
#include <memory>
#include <string>

#include <toml++/toml.h>

#include "rig/core/gpio.hpp"
#include "rig/gpio/line_rig_io.hpp"

namespace rig::gpio {

// What [gpio] says. Line names are GPIO line names (gpioinfo / gpiofind).
struct GpioConfig {
  std::string chip;  // optional: chip name, path or label; empty = search every chip
  std::string power, estop;  // required
  std::string lamp_ready, lamp_running, lamp_pass, lamp_fail;  // optional
  bool power_active_low = false;
  bool estop_active_low = true;  // fail-safe default: a normally-closed loop, a cut wire reads as e-stop
  std::string consumer = "rig";
};

// [gpio] keys: chip, power, estop, lamp_ready, lamp_running, lamp_pass,
// lamp_fail, power_active_low, estop_active_low, consumer. ConfigError
// (file:line) for unknown keys, missing or empty names.
GpioConfig parse_gpio_config(const toml::table& gpio_cfg);

// Opens the chip(s) and requests the lines. A chip or line that does not exist
// => HardwareError naming the config key and the line name.
std::unique_ptr<LineDriver> open_gpiod_lines(const GpioConfig& cfg);

std::unique_ptr<RigIo> connect_gpio(const toml::table& gpio_cfg);

}  // namespace rig::gpio
