#include "plant/emulated/world.hpp"

#include <algorithm>
#include <cmath>

#include "plant/firmware/inprocess_dut.hpp"
#include "plant/table/table_emulator.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"
#include "plant/table/table_emulator.hpp"
#include "rig/modbus/table_client.hpp"

namespace rig::plant {

namespace {
// A DUT that has not streamed for this long (simulated) is reported silent, as the CAN link does.
constexpr double kSilenceLimitS = 0.1;
}  // namespace

// Counts the DUT's output samples, whichever path (direct or CAN firmware) draws them: the
// figure behind the real-time factor `rig run` reports.
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

EmulatedPlant::EmulatedPlant(const toml::table& plant_cfg) : link_(*this) {
  cfg::check_keys(plant_cfg, {"seed", "link", "dut", "table"}, "plant");
  const auto seed = static_cast<uint64_t>(cfg::get_int(plant_cfg, "seed", 1, 0));
  dut_ = std::make_unique<CountingSource>(make_dut_source(cfg::get_table(plant_cfg, "dut"), seed), samples_);
  // Separate, fixed streams per component: the table's repeatability does not
  // shift when the DUT model draws more or fewer random numbers.
  table_emu_ = make_table_emulator(cfg::get_table(plant_cfg, "table"), seed ^ 0x7ab1e5eedULL);
  clock_.set_advance([this](double dt) { advance(dt); });
  table_ = modbus::make_inprocess_table(*table_emu_, clock_);
  const std::string link = cfg::get_string(plant_cfg, "link", std::string("can"));
  if (link == "can") {
    can_link_ = link::make_inprocess_dut(*dut_, clock_);
  } else if (link != "direct") {
    throw ConfigError(cfg::where(*plant_cfg.get("link")) + ": [plant] link must be \"can\" or \"direct\"");
  }
}

DutLink& EmulatedPlant::dut() {
  if (can_link_) return *can_link_;
  return link_;
}

uint32_t EmulatedPlant::next_seq() const {
  return can_link_ ? static_cast<uint32_t>(can_link_->firmware().sample_counter()) : seq_;
}

void EmulatedPlant::inject_drop(uint32_t from_seq, uint32_t count) {
  drops_.push_back({from_seq, count});
  if (can_link_) {
    can_drops_.push_back({from_seq, count});
    FirmwareFaults f;
    f.drop_samples = can_drops_;
    can_link_->firmware().set_faults(f);
  }
}

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
    io_.trip_estop();
  }
  table_emu_->step(dt);
  dut_->set_table_angle_deg(table_emu_->actual_angle_deg());
  // The DUT runs whenever powered; its counter is free-running like the firmware's.
  sample_acc_ += dt * dut_->output_rate_hz();
  const auto n = static_cast<long>(std::floor(sample_acc_ + 1e-9));
  sample_acc_ -= static_cast<double>(n);
  if (!io_.dut_power()) return;  // an unpowered DUT is silent
  if (can_link_) {
    can_link_->step(dt);
    return;
  }
  for (long i = 0; i < n; ++i) {
    Sample s;
    s.seq = seq_++;
    dut_->next(s.x_g, s.y_g);
    if (dut_->filter().enabled) s.status |= sample_status::kFilterOn;
    if (!link_.streaming_) continue;
    const bool dropped = std::any_of(drops_.begin(), drops_.end(), [&](const auto& d) {
      return s.seq - d.first < d.second;  // unsigned: wraps correctly
    });
    if (!dropped) link_.deliver(s);
  }
}

void DirectDutLink::deliver(const Sample& in) {
  Sample s = in;
  if (last_seq_) {
    const uint32_t expected = *last_seq_ + 1;
    const uint32_t ahead = s.seq - expected;
    if (ahead != 0) {
      if (ahead < 0x80000000u) {  // forward jump: a gap
        ++stats_.gaps;
        stats_.lost += ahead;
        if (stats_.gap_list.size() < 1000) stats_.gap_list.push_back({expected, ahead});
        s.status |= sample_status::kGapBefore;
      } else {  // behind: duplicate or late
        ++stats_.duplicates;
        return;
      }
    }
  }
  last_seq_ = s.seq;
  ++stats_.received;
  queue_.push_back(s);
}

DutInfo DirectDutLink::info(const CancelToken& cancel) {
  cancel.throw_if_requested();
  if (!world_.io_.dut_power()) throw HardwareError("DUT does not answer 'read info': it is not powered");
  return {world_.dut_->serial(), "emulated-fw 1.0", world_.dut_->temperature_c(), world_.dut_->output_rate_hz()};
}

void DirectDutLink::start_stream(const CancelToken& cancel) {
  cancel.throw_if_requested();
  if (!world_.io_.dut_power()) throw HardwareError("DUT does not answer 'start stream': it is not powered");
  queue_.clear();
  last_seq_.reset();
  streaming_ = true;
}

void DirectDutLink::stop_stream() noexcept {
  streaming_ = false;
  queue_.clear();
}

std::size_t DirectDutLink::read(std::span<Sample> out, const CancelToken& cancel) {
  if (!streaming_) throw HardwareError("read from the DUT stream while it is stopped");
  double silent = 0;
  while (queue_.size() < out.size()) {
    const std::size_t before = queue_.size();
    const double dt = static_cast<double>(out.size() - queue_.size()) / world_.dut_->output_rate_hz();
    world_.clock_.sleep_for(dt, cancel);
    if (queue_.size() == before) {
      silent += dt;
      if (silent >= kSilenceLimitS)
        throw HardwareError("DUT stream silent for " + std::to_string(static_cast<int>(silent * 1000)) +
                            " ms (power " + (world_.io_.dut_power() ? "on" : "OFF") + ")");
    } else {
      silent = 0;
    }
  }
  std::copy_n(queue_.begin(), out.size(), out.begin());
  queue_.erase(queue_.begin(), queue_.begin() + static_cast<std::ptrdiff_t>(out.size()));
  return out.size();
}

void DirectDutLink::set_filter(const FilterConfig& f, const CancelToken& cancel) {
  cancel.throw_if_requested();
  if (!world_.io_.dut_power()) throw HardwareError("DUT does not answer 'set filter': it is not powered");
  world_.dut_->set_filter(f);
}

FilterConfig DirectDutLink::get_filter(const CancelToken& cancel) {
  cancel.throw_if_requested();
  return world_.dut_->filter();
}

}  // namespace rig::plant
