// The paper's procedure (docs/method.md A, B, C) run directly on the emulated DUT and
// evaluated with the rig's analysis library: the calibration harness shared by
// the calibration test and bench/plant/dut_calibrate.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "plant/dut/emulated_dut.hpp"
#include "analysis/noise_terms.hpp"

namespace rig::plant::calib {

struct Spec {
  int runs = 12;               // procedure A: alternating U10/U20
  double run_s = 100;
  double move_s = 10;          // table move + settle between runs (the DUT keeps running)
  double repeat_sd_deg = 2e-3; // table positioning repeatability (7 arcsec)
  double inrun_s = 1800;       // procedure B at U10
  double capture_s = 3600;     // procedure C raw capture at U10
  uint64_t table_seed = 7;
  std::string taus = "log:100";  // the Allan tau grid of profiles/paper.toml ([analysis].taus)
};

struct Result {
  std::vector<double> x10, x20;  // the 100 s means
  double bias = 0, base_error = 0;
  double b_gost_100 = 0, b_gost_200 = 0;
  analysis::NoiseTerms nt_x, nt_y;  // Allan noise terms of the capture (x and filtered y)
  std::vector<analysis::DevPoint> adev_x, adev_y;
  double rms_x = 0, rms_y = 0;      // RMS error of x, y over the capture
};

// Runs A, B and C in sequence on `dut` (power-on to the end, time never stops).
Result run(EmulatedDut& dut, const Spec& spec);
// B as sigma_min / 0.664 over tau >= tau_lo: the flat level read off the rig's OADEV
// curve directly (used where the paper's polynomial finds no inflection, see docs/plant.md).
double b_from_minimum(const std::vector<analysis::DevPoint>& adev, double tau_lo = 10);
// Allan noise terms of one record at `rate_hz`: OADEV on the tau grid `taus` (the paper
// profile's log:100, Stable32's stop ratio tau <= T/4) and noise_terms, as the rig's
// procedure does (procedures/acceptance allan_channel).
analysis::NoiseTerms allan_terms(const std::vector<double>& v, double rate_hz,
                                 std::vector<analysis::DevPoint>* adev = nullptr,
                                 const std::string& taus = "log:100");

}  // namespace rig::plant::calib
