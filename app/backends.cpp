#include "app/backends.hpp"

#include "firmware_link/connect.hpp"
#include "procedures/acceptance/loop_phase.hpp"
#include "plant/emulated/world.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/gpio/gpiod_lines.hpp"
#include "rig/modbus/table_client.hpp"

namespace rig::cli {

namespace {

[[noreturn]] void not_open(const char* what) {
  throw std::logic_error(std::string("no device is open (the resume only computes from the kept captures): ") + what);
}

// Time does not pass for devices that are not open: the clock reads the device time the run had
// reached (for the report), and a wait is a request to a device.
class HeldClock final : public Clock {
 public:
  explicit HeldClock(double t_s) : t_s_(t_s) {}
  double now_s() const override { return t_s_; }
  void sleep_for(double, const CancelToken&) override { not_open("a wait on the rig clock"); }

 private:
  double t_s_;
};

class UnopenedTable final : public RotaryTable {
 public:
  TableStatus status() override { not_open("table status"); }
  void home(const CancelToken&) override { not_open("table homing"); }
  void move_to(double, const CancelToken&) override { not_open("table move"); }
  void stop() noexcept override {}
  void quick_stop() noexcept override {}
  std::string describe() const override { return "table not opened"; }
};

class UnopenedDut final : public DutLink {
 public:
  DutInfo info(const CancelToken&) override { not_open("DUT identity"); }
  void start_stream(const CancelToken&) override { not_open("DUT stream"); }
  void stop_stream() noexcept override {}
  std::size_t read(std::span<Sample>, const CancelToken&) override { not_open("DUT stream"); }
  void set_filter(const FilterConfig&, const CancelToken&) override { not_open("DUT filter"); }
  FilterConfig get_filter(const CancelToken&) override { not_open("DUT filter"); }
  LinkStats stats() const override { return {}; }
  void reset_stats() override {}
  std::string describe() const override { return "DUT link not opened"; }
  LoopTestResponse loop_test(const LoopTestRequest&, const CancelToken&) override { not_open("DUT loop test"); }
};

class UnopenedIo final : public RigIo {
 public:
  void set_dut_power(bool on) override {
    if (on) not_open("DUT power");
  }
  bool dut_power() const override { return false; }
  bool estop_active() const override { return false; }
  void set_lamp(Lamp, bool) override {}  // no lamp to light: the verdict is in the passport and the exit code
  void on_estop(std::function<void()>) override {}
  std::string describe() const override { return "rig I/O not opened"; }
};

}  // namespace

Backends::Backends() = default;
Backends::~Backends() = default;
Backends::Backends(Backends&&) noexcept = default;
Backends& Backends::operator=(Backends&&) noexcept = default;

Devices Backends::devices() { return Devices{*table_ptr, *dut_ptr, *io_ptr, *clock_ptr, plant}; }

Backends make_emulated(const toml::table& plant_cfg, const std::string& serial) {
  Backends b;
  b.plant = "emulated";
  b.emulated = std::make_unique<plant::EmulatedPlant>(plant_cfg, serial);
  b.clock_ptr = &b.emulated->clock();
  b.table_ptr = &b.emulated->table();
  b.dut_ptr = &b.emulated->dut();
  b.io_ptr = &b.emulated->io();
  return b;
}

Backends make_hardware(const toml::table& hw, acceptance::Profile& p) {
  // Configuration before devices: a mistake in any section (drive map included) is exit 2
  // naming the file, not hidden behind a device that cannot be opened.
  validate_hardware(hw, kRunSections);
  apply_procedure_angles(hw, p);
  Backends b;
  b.plant = "hardware";
  b.clock = std::make_unique<RealClock>();
  b.clock_ptr = b.clock.get();
  // [dut.design]: the DUT type's loop, the loop figures' labelled fallback without a loop test
  // (checked with the whole hardware file before any device opens: app/hardware_file).
  p.design_model = acceptance::read_design_model(*cfg::get_table(hw, "dut", true));
  // GPIO first: the e-stop watch must be live before anything moves.
  b.io = gpio::connect_gpio(*cfg::get_table(hw, "gpio", true));
  b.io_ptr = b.io.get();
  b.table = modbus::connect_table(*cfg::get_table(hw, "table", true), *b.clock);
  b.table_ptr = b.table.get();
  b.dut = link::connect_dut(*cfg::get_table(hw, "dut", true), *b.clock);
  b.dut_ptr = b.dut.get();
  return b;
}

Backends make_unopened(const std::string& plant, double device_time_s) {
  Backends b;
  b.plant = plant;
  b.clock = std::make_unique<HeldClock>(device_time_s);
  b.clock_ptr = b.clock.get();
  b.table = std::make_unique<UnopenedTable>();
  b.table_ptr = b.table.get();
  b.dut = std::make_unique<UnopenedDut>();
  b.dut_ptr = b.dut.get();
  b.io = std::make_unique<UnopenedIo>();
  b.io_ptr = b.io.get();
  return b;
}

}  // namespace rig::cli
