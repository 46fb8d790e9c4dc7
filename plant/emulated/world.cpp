#include "plant/emulated/world.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "firmware_link/dbc_stream.hpp"
#include "plant/firmware/firmware_config.hpp"
#include "plant/firmware/firmware_emulator.hpp"
#include "plant/firmware/inprocess_dut.hpp"
#include "plant/table/table_emulator.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/modbus/table_client.hpp"

namespace rig::plant {

// Counts the DUT's output samples as the firmware emulator draws them: the figure behind
// the real-time factor `rig run` reports.
class EmulatedPlant::CountingSource final : public DutSourceWrapper {
 public:
  CountingSource(std::unique_ptr<DutSource> inner, std::uint64_t& count)
      : DutSourceWrapper(std::move(inner)), count_(count) {}
  void next(float& x_g, float& y_g) override {
    ++count_;
    DutSourceWrapper::next(x_g, y_g);
  }

 private:
  std::uint64_t& count_;
};

void check_plant_keys(const toml::table& plant_cfg) {
  // `link` selected a second, direct DUT path that bypassed the CAN client; it is gone, and a
  // profile that still names it fails here rather than silently running another path.
  if (const toml::node* l = plant_cfg.get("link"))
    throw ConfigError(cfg::where(*l) + ": [plant] link was removed: the emulated DUT is always reached through the "
                                       "CAN link (the in-process bus and the firmware emulator); delete this key");
  cfg::check_keys(plant_cfg, {"seed", "dut", "table", "firmware"}, "plant");
}

EmulatedPlant::EmulatedPlant(const toml::table& plant_cfg, const std::string& serial) {
  check_plant_keys(plant_cfg);
  const auto seed = static_cast<uint64_t>(cfg::get_int(plant_cfg, "seed", 1, 0));
  dut_ = std::make_unique<CountingSource>(make_dut_source(cfg::get_table(plant_cfg, "dut"), seed, serial), samples_);
  // The firmware sends one sample per tick: a DUT model at another output rate would be
  // streamed (and its captures labelled) at the tick's rate, not its own.
  const double tick_hz = 1e9 / static_cast<double>(kFirmwareTickNs);
  if (std::abs(dut_->output_rate_hz() - tick_hz) > 1e-9 * tick_hz) {
    const toml::node* n = plant_cfg.at_path("dut.loop.output_rate_hz").node();
    const std::string why = "the emulated firmware streams one sample per " + std::to_string(kFirmwareTickNs / 1000) +
                            " us tick, so the emulated DUT's output rate must be " +
                            std::to_string(std::llround(tick_hz)) + " Hz";
    if (n) cfg::reject(*n, "output_rate_hz", why);
    throw ConfigError("[plant.dut.loop] output_rate_hz = " + std::to_string(dut_->output_rate_hz()) + ": " + why);
  }
  // Separate, fixed streams per component: the table's repeatability does not
  // shift when the DUT model draws more or fewer random numbers.
  table_emu_ = make_table_emulator(cfg::get_table(plant_cfg, "table"), seed ^ 0x7ab1e5eedULL);
  clock_.set_advance([this](double dt) { advance(dt); });
  table_ = modbus::make_inprocess_table(*table_emu_, clock_);
  auto lines = std::make_unique<gpio::SimLines>();
  lines_ = lines.get();
  io_ = std::make_unique<gpio::LineRigIo>(std::move(lines));
  // The rig side mirrors the firmware, as a hardware file's [dut] section would describe it.
  link::InProcessDutOptions lo;
  lo.firmware = firmware_options(cfg::get_table(plant_cfg, "firmware"));
  lo.link.commands = lo.firmware.commands;
  if (lo.firmware.stream) lo.link.stream = lo.firmware.stream->layout();
  // The same tick for a described stream: a rate_hz other than the tick's labelled the captures
  // 1000 Hz while the layout said otherwise (a review).
  if (lo.link.stream && std::abs(lo.link.stream->rate_hz() - tick_hz) > 1e-9 * tick_hz) {
    const auto& kw = lo.link.stream->spec().key_where;
    const auto at = kw.find("rate_hz");
    char rate[32];
    std::snprintf(rate, sizeof rate, "%.9g", lo.link.stream->rate_hz());
    throw ConfigError((at != kw.end() ? at->second : std::string("[plant.firmware.stream]")) + ": rate_hz = " + rate +
                      ": the emulated firmware streams one sample per " + std::to_string(kFirmwareTickNs / 1000) +
                      " us tick, so its stream's rate must be " + std::to_string(std::llround(tick_hz)) + " Hz");
  }
  link_ = link::make_inprocess_dut(*dut_, clock_, lo);
}

DutLink& EmulatedPlant::dut() { return *link_; }

uint32_t EmulatedPlant::next_seq() const { return static_cast<uint32_t>(link_->firmware().sample_counter()); }

void EmulatedPlant::inject_drop(uint32_t from_seq, uint32_t count) {
  drops_.push_back({from_seq, count});
  FirmwareFaults f;
  f.drop_samples = drops_;
  link_->firmware().set_faults(f);
}

std::vector<uint64_t> EmulatedPlant::drop_hits() const { return link_->firmware().stats().drop_hits; }

EmulatedPlant::~EmulatedPlant() = default;

void EmulatedPlant::advance(double dt) {
  const double t_end = clock_.now_s() + dt;
  for (auto it = actions_.begin(); it != actions_.end();) {
    if (it->first <= t_end) {
      auto fn = std::move(it->second);
      it = actions_.erase(it);
      fn();
    } else {
      ++it;
    }
  }
  if (estop_at_ && *estop_at_ <= t_end) {
    estop_at_.reset();
    // The rig's own e-stop logic (LineRigIo's watcher) handles the edge; the world waits for
    // it so that power is off and the rig's handler has run within this slice, every run.
    lines_->drive_estop_handled(true);
  }
  table_emu_->step(dt);
  dut_->set_table_angle_deg(table_emu_->actual_angle_deg());
  if (!io_->dut_power()) return;  // an unpowered DUT is silent
  link_->step(dt);
}

}  // namespace rig::plant
