// The U10/U20 acceptance procedure of docs/method.md as executive phases:
//   bring-up  power the DUT, identify it, configure the output filter, home the table
//   runNN-Uxx 12 runs of run_s each, alternating orientation (procedure A)
//   bias      formulas (3), (4) with the sign rule, GOST R 8.736 statistics
//   in-run    one run of in_run_s at U10 (procedure B) -> B by the Russian method
//   raw       the raw 1 kHz capture (procedure C) -> Allan deviation, noise terms,
//             RMS error, PSD; the same for the filtered output y(t)
//   loop      the DUT's loop test, its records kept (loop-test.csv)
//   loop-figures  closed-loop bandwidth and settling time with the output filter, read off them
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "analysis/gost.hpp"
#include "procedures/acceptance/profile.hpp"
#include "procedures/acceptance/state.hpp"
#include "rig/core/table.hpp"
#include "rig/executive/executive.hpp"

namespace rig::acceptance {

struct RunOptions {
  std::optional<std::string> expected_serial;  // --serial: the DUT must report this
};

// What the table's moves cost in device time, for the phases' planned durations (the dry-run
// estimate, the progress ETA). The defaults are the emulated drive's power-on profile and
// settle time (docs/table-registers.md, [plant.table]) and the table client's defaults (the
// hardware file's [table] settle_s, poll_s), both from rig/core/table.hpp's table_defaults: a
// hardware file or [plant.table] that sets others makes the plan that much off unless the
// caller passes them.
struct TableTiming {
  double velocity_dps = table_defaults::kVelocityDps;
  double accel_dps2 = table_defaults::kAccelDps2;
  double drive_settle_s = table_defaults::kDriveSettleS;  // the drive's in-position settle
  double settle_s = table_defaults::kClientSettleS;       // the client's: in position held this long
  double poll_s = table_defaults::kClientPollS;           // the client's status polling: the wait ends on a poll
  double home_deg = 0.0;        // homing leaves the table here (ACTUAL_POS becomes 0)
  // A move_to from `from_deg` to `to_deg`: the trapezoid, both settle times and the last poll
  // (a move to where the table already is costs the settle times alone).
  double move_s(double from_deg, double to_deg) const;
};

// What the DUT can be asked, as its link's configuration declares it (a hardware file's [dut],
// the emulated firmware's options): a loop test it cannot run is planned at no device time (the
// phase only records that it was skipped).
struct DutAbilities {
  bool commands = true;   // a command channel: identify, set output filter, loop test
  bool loop_test = true;  // the firmware runs the loop test
  // Why the rig's link refuses the loop test from its own options, asking the DUT nothing (no
  // command channel, [dut] loop_test = false; link::loop_test_refused_by), "" where it asks the
  // DUT: that phase then uses no device (Phase::uses_devices).
  std::string link_loop_test_refusal = {};
  bool runs_loop_test() const { return commands && loop_test; }
};

// The phases, each with the measures it declares (name, unit, description) and its planned
// device time: each recording's move from where the previous one left the table, its settle
// and record; the loop test's steps (none where `dut` cannot run it; no retries counted;
// bring-up, i.e. the DUT's power-up and homing, is not a phase). The phases read and write
// `state` (kept alive by the caller, as `p`).
std::vector<Phase> build_phases(const Profile& p, ProcedureState& state, const TableTiming& table = {},
                                const DutAbilities& dut = {});

// Declares the phases' measures with the profile's limits, in passport order (phase
// order, then accuracy_class, which is required when the profile has classes).
void declare_values(const Profile& p, const std::vector<Phase>& phases, MeasurementSet& values);

// Bring-up sequence (runs on every start and resume). A DUT without a command channel
// (DutLink::command_channel) is not asked anything: its identity is identity_without_commands().
void bring_up(PhaseContext& ctx, const Profile& p, const RunOptions& opt, DutState& state);

// The identity of a DUT that cannot be asked: the serial from --serial (none => ConfigError),
// and the bring-up steps skipped -- identify, set output filter, loop test -- each with `why`.
DutIdentity identity_without_commands(const Profile& p, const RunOptions& opt, const std::string& why);

// Formulas (3), (4) of docs/method.md with the sign rule: g_dA enters (1) with +
// when mean(x10) > mean(x20). Exposed for tests.
struct BiasBaseError {
  double bias = 0;        // g_sist, formula (3)
  double base_error = 0;  // g_dA, formula (4), >= 0 by the sign rule
  int sign_u10 = +1;      // the sign with which g_dA enters x10
  // GOST 95 % half-widths over the pairs; none from a single pair (no scatter to take them from)
  std::optional<double> bias_ci_half, base_ci_half;
  // GOST R 8.736's processing of the pairs' summands of (3) and (4), two or more pairs: the
  // interval above and the repeated Grubbs test (outliers indexed by pair, reported, not removed).
  std::optional<analysis::GostSummary> bias_gost, base_gost;
};
BiasBaseError bias_and_base_error(const std::vector<double>& x10, const std::vector<double>& x20);

// The reason's note on the Grubbs test of the pairs' summands (`g` of `value`, "bias" or
// "base_error"); pairs[k] = the k-th pair's run numbers (U10, U20). An outlier is also warned of
// in `log` (when given). Exposed for tests.
std::string grubbs_note(const analysis::GostSummary& g, const std::vector<std::pair<std::size_t, std::size_t>>& pairs,
                        spdlog::logger* log, const char* value);

// Accuracy class from B: 1-based index of the first class with max_b_g >= b.
std::optional<std::size_t> accuracy_class(const std::vector<AccuracyClass>& classes, double b);

}  // namespace rig::acceptance
