// The `loop` phase: the closed loop's figures of criterion 2 (docs/method.md "Spectral analysis and
// the output filter") measured on the DUT by its loop test (docs/can-protocol.md "Loop test"),
// never taken from a model: the DUT steps a test torque inside its loop, the rig records each
// step's response at the loop rate into the run folder (kLoopTestFile) and reads off the
// settling time and the 0.5-level bandwidth of the filtered output y with 95 % intervals over
// the steps. A DUT without a loop test leaves both values null with the reason, unless the
// hardware file names the DUT type's design model ([dut.design]): then its figures, labelled
// "design model", computed by design/ for the profile's filter.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "procedures/acceptance/profile.hpp"
#include "procedures/acceptance/state.hpp"
#include "rig/core/dut_link.hpp"
#include "rig/executive/executive.hpp"

namespace rig::acceptance {

inline constexpr const char* kLoopTestFile = "loop-test.csv";  // relative to the run folder

void phase_loop(PhaseContext& ctx, const Profile& p, DutState& st);

// The hardware file's optional [dut.design] ([dut.design.loop] and [dut.design.regulator], the
// keys of design/loop_params.hpp; absent keys keep design/'s defaults): nullopt without it.
// Unknown keys and values out of range => ConfigError naming file:line.
std::optional<Profile::DesignModel> read_design_model(const toml::table& dut);

// The raw records as loop-test.csv (docs/can-protocol.md "Loop test"): a comment header, then
// one line per sample: step, index, t_s (from the step), x_g, y_g.
std::string loop_test_csv(const LoopTestResponse& r);

// Figures of a loop test's records as analysis.json's "loop" carries them (the report draws its
// step and amplitude curves), with the two passport values' intervals.
nlohmann::json loop_test_figures(const LoopTestResponse& r);

}  // namespace rig::acceptance
