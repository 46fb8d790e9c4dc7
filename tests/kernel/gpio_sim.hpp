// The "hardware" side of a gpio-sim chip, through its sysfs attributes
// (Documentation/admin-guide/gpio/gpio-sim.rst): sim_gpioN/value is the level
// the consumer drives, sim_gpioN/pull what an external switch would do.
#pragma once
#include <chrono>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>

namespace rig::kernel_test {

class GpioSim {
 public:
  explicit GpioSim(std::string chip) : chip_(std::move(chip)) {}
  std::string attr(int line, const char* name) const {
    return "/sys/bus/gpio/devices/" + chip_ + "/sim_gpio" + std::to_string(line) + "/" + name;
  }
  int value(int line) const {
    std::ifstream f(attr(line, "value"));
    int v = -1;
    if (!(f >> v)) throw std::runtime_error("cannot read " + attr(line, "value"));
    return v;
  }
  void pull(int line, const char* how) const {
    std::ofstream f(attr(line, "pull"));
    f << how;
    f.flush();
    if (!f) throw std::runtime_error("cannot write " + attr(line, "pull"));
  }
  // Opens the e-stop loop (pull-down on an active-low input) and polls the
  // power line until it reads 0; returns the seconds from the edge to that.
  double trip_and_time_power_off(int estop_line, int power_line, double timeout_s) const {
    using clk = std::chrono::steady_clock;
    const auto t0 = clk::now();
    pull(estop_line, "pull-down");
    while (value(power_line) != 0) {
      if (clk::now() - t0 > std::chrono::duration<double>(timeout_s))
        throw std::runtime_error("power line still high " + std::to_string(timeout_s) + " s after the e-stop edge");
    }
    return std::chrono::duration<double>(clk::now() - t0).count();
  }

 private:
  std::string chip_;
};

}  // namespace rig::kernel_test
