// Test helpers for the link tests: a deterministic DutSource whose output is a
// known function of the sample counter, so a value read through the protocol
// can be checked exactly against what was produced.
#pragma once
#include <string>

#include "plant/emulated/dut_source.hpp"

namespace rig::link::testing {

class RampSource final : public plant::DutSource {
 public:
  static float x_of(uint64_t k) { return static_cast<float>(static_cast<double>(k % 100000) * 1e-6 - 0.05); }
  static float y_of(uint64_t k) { return -x_of(k); }
  double output_rate_hz() const override { return 1000.0; }
  void set_table_angle_deg(double) override {}
  void next(float& x, float& y) override {
    x = x_of(k_);
    y = y_of(k_);
    ++k_;
  }
  void set_filter(const FilterConfig& f) override { f_ = f; }
  FilterConfig filter() const override { return f_; }
  double temperature_c() const override { return 23.25; }
  std::string serial() const override { return serial_; }
  std::string serial_ = "QPA-2026-000117";

 private:
  uint64_t k_ = 0;
  FilterConfig f_;
};

}  // namespace rig::link::testing
