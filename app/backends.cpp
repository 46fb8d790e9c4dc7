#include "app/backends.hpp"
#include "app/station_stop.hpp"

#include <stdexcept>

#include "firmware_link/connect.hpp"
#include "procedures/acceptance/loop_phase.hpp"
#include "plant/emulated/world.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/gpio/gpiod_lines.hpp"
#include "rig/modbus/table_client.hpp"

namespace rig::cli {

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

Backends make_hardware(const toml::table& hw, acceptance::Profile& p, const std::string& table_id) {
  // Configuration before devices: a mistake in any section (drive map included) is exit 2
  // naming the file, not hidden behind a device that cannot be opened.
  validate_hardware(hw, kRunSections);
  apply_procedure_angles(hw, p);
  Backends b;
  b.plant = "hardware";
  b.clock = std::make_unique<RealClock>();
  b.clock_ptr = b.clock.get();
  // GPIO first: the e-stop watch must be live before anything moves.
  b.io = gpio::connect_gpio(*cfg::get_table(hw, "gpio", true));
  b.io_ptr = b.io.get();
  // A `rig table stop` from this station during a move ends the run as the operator's abort.
  const toml::table& table = *cfg::get_table(hw, "table", true);
  b.table = std::make_unique<StationStoppableTable>(modbus::connect_table(table, *b.clock), table_id);
  b.table_ptr = b.table.get();
  b.dut = link::connect_dut(*cfg::get_table(hw, "dut", true), *b.clock);
  b.dut_ptr = b.dut.get();
  return b;
}

namespace {
// One object behind the four seams: none of them is open.
class Unopened final : public RotaryTable, public DutLink, public RigIo, public Clock {
 public:
  Unopened(double device_time_s, std::string loop_test_refusal)
      : device_time_s_(device_time_s), loop_test_refusal_(std::move(loop_test_refusal)) {}
  [[noreturn]] static void refuse(const char* what) {
    throw std::logic_error(std::string(what) + ": no device is open (every phase left computes from the run's records)");
  }
  TableStatus status() override { refuse("table status"); }
  void home(const CancelToken&) override { refuse("table homing"); }
  void move_to(double, const CancelToken&) override { refuse("table move"); }
  void stop() noexcept override {}
  void quick_stop() noexcept override {}
  DutInfo info(const CancelToken&) override { refuse("DUT identification"); }
  void start_stream(const CancelToken&) override { refuse("DUT stream"); }
  void stop_stream() noexcept override {}
  std::size_t read(std::span<Sample>, const CancelToken&) override { refuse("DUT stream"); }
  void set_filter(const FilterConfig&, const CancelToken&) override { refuse("DUT filter"); }
  FilterConfig get_filter(const CancelToken&) override { refuse("DUT filter"); }
  LinkStats stats() const override { return {}; }
  void reset_stats() override {}
  void set_dut_power(bool on) override {
    if (on) refuse("DUT power");
  }
  bool dut_power() const override { return false; }
  bool estop_active() const override { return false; }
  void set_lamp(Lamp, bool) override {}
  void on_estop(std::function<void()>) override {}
  LoopTestResponse loop_test(const LoopTestRequest&, const CancelToken&) override {
    if (loop_test_refusal_.empty()) refuse("DUT loop test");
    LoopTestResponse r;  // as the link answers it, from its options alone
    r.reason = loop_test_refusal_;
    return r;
  }
  DutCommandChannel command_channel() const override { refuse("DUT command channel"); }
  std::optional<std::pair<double, double>> travel_deg(const CancelToken&) override { refuse("table travel"); }
  std::string describe() const override { return "not opened"; }
  // Where the run left it: a phase that computes reports its progress against it.
  double now_s() const override { return device_time_s_; }
  void sleep_for(double, const CancelToken&) override { refuse("device clock"); }

 private:
  double device_time_s_;
  std::string loop_test_refusal_;
};
}  // namespace

Backends make_unopened(const std::string& plant, double device_time_s, const std::string& loop_test_refusal) {
  Backends b;
  b.plant = plant;
  auto none = std::make_shared<Unopened>(device_time_s, loop_test_refusal);
  b.unopened = none;
  b.clock_ptr = none.get();
  b.table_ptr = none.get();
  b.dut_ptr = none.get();
  b.io_ptr = none.get();
  return b;
}

}  // namespace rig::cli
