// The U10/U20 acceptance procedure of docs/method.md as executive phases:
//   bring-up  power the DUT, identify it, configure the output filter, home the table
//   runNN-Uxx 12 runs of run_s each, alternating orientation (procedure A)
//   bias      formulas (3), (4) with the sign rule, GOST R 8.736 statistics
//   in-run    one run of in_run_s at U10 (procedure B) -> B by the Russian method
//   raw       the raw 1 kHz capture (procedure C) -> Allan deviation, noise terms,
//             RMS error, PSD; the same for the filtered output y(t)
//   loop      closed-loop bandwidth and settling time with the output filter
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "procedures/acceptance/profile.hpp"
#include "rig/executive/executive.hpp"

namespace rig::acceptance {

struct RunOptions {
  std::optional<std::string> expected_serial;  // --serial: the DUT must report this
};

// Declares every passport value (unit, limits) in passport order.
void declare_values(const Profile& p, MeasurementSet& values);

// Bring-up sequence (runs on every start and resume).
void bring_up(PhaseContext& ctx, const Profile& p, const RunOptions& opt);

std::vector<Phase> build_phases(const Profile& p);

// Formulas (3), (4) of docs/method.md with the sign rule: g_dA enters (1) with +
// when mean(x10) > mean(x20). Exposed for tests.
struct BiasBaseError {
  double bias = 0;        // g_sist, formula (3)
  double base_error = 0;  // g_dA, formula (4), >= 0 by the sign rule
  int sign_u10 = +1;      // the sign with which g_dA enters x10
  double bias_ci_half = 0, base_ci_half = 0;  // GOST 95 % half-widths over the pairs
};
BiasBaseError bias_and_base_error(const std::vector<double>& x10, const std::vector<double>& x20);

// Accuracy class from B: 1-based index of the first class with max_b_g >= b.
std::optional<std::size_t> accuracy_class(const std::vector<AccuracyClass>& classes, double b);

}  // namespace rig::acceptance
