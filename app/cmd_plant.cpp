// `rig plant serve`: the emulated table and DUT in real time, as separate
// endpoints reached through the real protocols (Modbus TCP/RTU, CAN), for
// integration tests and technicians' training.
#include <charconv>
#include <cmath>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <system_error>

#include <fmt/format.h>

#include "plant/emulated/dut_source.hpp"
#include "plant/emulated/plant_config.hpp"
#include "plant/firmware/can_dut_server.hpp"
#include "plant/firmware/firmware_config.hpp"
#include "plant/table/cia402_drive.hpp"
#include "plant/table/table_emulator.hpp"
#include "plant/table/table_server.hpp"
#include "procedures/acceptance/profile.hpp"
#include "app/commands.hpp"
#include "app/number_option.hpp"
#include "app/endpoint_option.hpp"
#include "rig/core/clock.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/executive/signals.hpp"
#include "rig/modbus/drive_map.hpp"

namespace rig::cli {

namespace {

// Couples the table to the DUT: before every output period the DUT sees the
// table's actual angle. Only the firmware thread calls into the DUT model;
// the table emulator is thread-safe.
class TableCoupledDut final : public plant::DutSourceWrapper {
 public:
  TableCoupledDut(std::unique_ptr<plant::DutSource> inner, plant::TableEmulator& table)
      : DutSourceWrapper(std::move(inner)), table_(table) {}
  void next(float& x, float& y) override {
    inner().set_table_angle_deg(table_.actual_angle_deg());
    inner().next(x, y);
  }

 private:
  plant::TableEmulator& table_;
};

struct ServeArgs {
  std::string modbus, rtu, can, profile = "paper", drive = "rig-v1", drive_map;
  double duration = 0;
  int unit = 1;
};

int serve(const ServeArgs& a) {
  if (a.modbus.empty() && a.rtu.empty() && a.can.empty())
    throw ConfigError("rig plant serve: give at least one endpoint: --modbus HOST:PORT, --rtu DEVICE or --can IFACE");
  CancelSource cancel;
  SignalWatcher signals(cancel);  // before the server threads start
  std::string source;
  const toml::table profile = acceptance::load_profile_table(a.profile, source);
  const acceptance::Profile p = acceptance::parse_profile(profile, source);
  const toml::table& plant_cfg = plant::plant_section(profile);
  plant::validate_plant_section(plant_cfg);  // the same check as rig run's, --dry-run's
  const plant::FirmwareOptions fw = plant::firmware_options(cfg::get_table(plant_cfg, "firmware"));
  const auto seed = static_cast<uint64_t>(cfg::get_int(plant_cfg, "seed", 1, 0));
  if (a.drive == "cia402" && a.drive_map.empty())
    throw ConfigError("rig plant serve: --drive cia402 needs --drive-map FILE (see drives/)");
  if (a.drive != "cia402" && !a.drive_map.empty())
    throw ConfigError("rig plant serve: --drive-map is for --drive cia402");
  std::optional<modbus::DriveMap> map;
  if (!a.drive_map.empty()) map = modbus::load_drive_map(a.drive_map);
  plant::TableParams tp = plant::table_params_from_toml(cfg::get_table(plant_cfg, "table"));
  if (map) {  // the drive's travel limits are the map's (a CiA 402 drive keeps them in 0x607D)
    tp.limit_neg_deg = map->limit_neg_deg;
    tp.limit_pos_deg = map->limit_pos_deg;
  }
  auto table = std::make_unique<plant::TableEmulator>(tp, seed ^ 0x7ab1e5eedULL);
  TableCoupledDut dut(plant::make_dut_source(cfg::get_table(plant_cfg, "dut"), seed), *table);
  std::unique_ptr<plant::Cia402Drive> cia;
  if (map) cia = std::make_unique<plant::Cia402Drive>(*table, *map);

  // A second server on the same emulator must not step it a second time.
  auto server = [&](const std::string& spec, bool steps) {
    if (!cia) return std::make_unique<plant::TableServer>(*table, spec, a.unit, steps);
    std::function<void(double)> step;
    if (steps) step = [d = cia.get()](double dt) { d->step(dt); };
    return std::make_unique<plant::TableServer>(*cia, step, spec, a.unit);
  };
  std::vector<std::unique_ptr<plant::TableServer>> tables;
  if (!a.modbus.empty()) tables.push_back(server("tcp:" + a.modbus, true));
  if (!a.rtu.empty()) tables.push_back(server("rtu:" + a.rtu, tables.empty()));
  for (auto& t : tables) {
    t->on_notice([](const std::string& text) { std::cerr << "table: " << text << std::endl; });
    t->start();
    std::cout << "table: modbus " << t->endpoint() << " unit " << a.unit
              << (map ? " drive cia402 \"" + map->name + "\" (" + map->path + ")" : std::string(" drive rig-v1"))
              << std::endl;
  }
  std::unique_ptr<plant::CanDutServer> can;
  if (!a.can.empty()) {
    can = std::make_unique<plant::CanDutServer>(dut, a.can, fw);
    can->start();
    std::cout << "dut: " << can->describe() << " serial " << dut.serial() << std::endl;
  }
  // A profile file is named as given, its profile name beside it (a file with base = "ci" read
  // "profile ci", the file nowhere: a review).
  const std::string shown = a.profile == p.name ? p.name : a.profile + ", named " + p.name;
  std::cout << "plant: serving (profile " << shown << ", seed " << seed << "); Ctrl-C to stop" << std::endl;
  RealClock clock;
  int rc = kExitPass;
  try {
    clock.sleep_for(a.duration > 0 ? a.duration : 1e12, cancel.token());
  } catch (const AbortedError&) {
    std::cout << "plant: " << cancel.token().reason() << ", stopping" << std::endl;
  }
  if (can) can->stop();
  for (auto& t : tables) t->stop();
  return rc;
}

}  // namespace

void add_plant(CLI::App& app, int& rc) {
  auto* plant = app.add_subcommand("plant", "The emulated plant as real endpoints");
  plant->require_subcommand(1);
  auto* sub = plant->add_subcommand("serve", "Serve the emulated table (Modbus) and DUT (CAN) in real time");
  auto a = std::make_shared<ServeArgs>();
  sub->add_option("--modbus", a->modbus, "Modbus TCP endpoint HOST:PORT or [IPv6]:PORT (PORT 0 picks a free port)")
      ->check(modbus_endpoint_option(EndpointOption::kServe));
  sub->add_option("--rtu", a->rtu, "Modbus RTU serial device DEVICE[,BAUD[,P,D,S]] (e.g. one end of a socat pty pair)")
      ->check(modbus_endpoint_option(EndpointOption::kSerial));
  sub->add_option("--unit", a->unit, "Modbus unit (slave) id")->capture_default_str()->check(CLI::Range(1, 247));
  sub->add_option("--drive", a->drive, "The emulated drive's protocol: rig-v1 (docs/table-registers.md) or cia402")
      ->check(CLI::IsMember({"rig-v1", "cia402"}))
      ->capture_default_str();
  sub->add_option("--drive-map", a->drive_map, "CiA 402 drive map the emulated drive serves (drives/*.toml)");
  sub->add_option("--can", a->can, "CAN interface for the DUT firmware emulator (e.g. vcan0)");
  sub->add_option("--profile", a->profile, "Profile whose [plant] section configures the emulated DUT and table")
      ->capture_default_str();
  sub->add_option("--duration", a->duration, "Stop after this many seconds (default: until SIGINT/SIGTERM)")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            double x = 0;
            const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), x);
            return ec == std::errc() && end == v.data() + v.size() && x > 0 && std::isfinite(x)
                       ? std::string()
                       : "'" + shown_ascii(v) + "'" + range_note(v) +
                             ": must be a number of seconds > 0 (leave it out to serve until SIGINT/SIGTERM)";
          },
          "SECONDS > 0"));
  sub->callback([a, &rc] { rc = serve(*a); });
}

}  // namespace rig::cli
