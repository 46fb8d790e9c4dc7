// The emulated DUT's physics as the rest of the plant sees it: one call per
// output period (1 kHz) returns the sample-and-held x(t), y(t) in g.
// Implemented in plant/dut (closed loop + noise); the firmware emulator reads from it.
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>

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
  // filter().enabled without copying the filter (the firmware asks every output period).
  virtual bool filter_enabled() const { return filter().enabled; }
  virtual double temperature_c() const = 0;
  virtual std::string serial() const = 0;
  // The loop test (LOOP_TEST, docs/can-protocol.md) needs the loop itself: a source that models
  // it returns its loop periods per output period (0: no loop, the firmware has no loop test)
  // and, in next_under_test(), advances one output period with a test torque equivalent to
  // `torque_g` of input acceleration inside the loop, writing the loop-rate x and y of the
  // period (loop_steps_per_output() values each). Returns whether the loop saturated (pick-off ADC or PWM duty clipped).
  virtual int loop_steps_per_output() const { return 0; }
  virtual bool next_under_test(double /*torque_g*/, std::span<float> /*x_loop*/, std::span<float> /*y_loop*/) {
    return false;
  }
};

// A DutSource wrapped around another: forwards everything; a wrapper overrides what it adds
// to (the plant's sample counter, `rig plant serve`'s table coupling).
class DutSourceWrapper : public DutSource {
 public:
  explicit DutSourceWrapper(std::unique_ptr<DutSource> inner) : inner_(std::move(inner)) {}
  double output_rate_hz() const override { return inner_->output_rate_hz(); }
  void set_table_angle_deg(double deg) override { inner_->set_table_angle_deg(deg); }
  void next(float& x_g, float& y_g) override { inner_->next(x_g, y_g); }
  void set_filter(const FilterConfig& f) override { inner_->set_filter(f); }
  FilterConfig filter() const override { return inner_->filter(); }
  bool filter_enabled() const override { return inner_->filter_enabled(); }
  double temperature_c() const override { return inner_->temperature_c(); }
  std::string serial() const override { return inner_->serial(); }
  int loop_steps_per_output() const override { return inner_->loop_steps_per_output(); }
  bool next_under_test(double torque_g, std::span<float> x_loop, std::span<float> y_loop) override {
    return inner_->next_under_test(torque_g, x_loop, y_loop);
  }

 protected:
  DutSource& inner() { return *inner_; }

 private:
  std::unique_ptr<DutSource> inner_;
};

// Builds the emulated DUT. `dut_cfg` is the [plant.dut] table of the profile
// (overrides on the default DUT profile), may be null. Same seed => bit-identical output.
// `serial`, when not empty, replaces the emulated DUT's own serial (rig run --serial in emulation).
std::unique_ptr<DutSource> make_dut_source(const toml::table* dut_cfg, uint64_t seed, const std::string& serial = {});

}  // namespace rig::plant
