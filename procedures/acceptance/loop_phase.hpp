// The closed loop's figures of criterion 2 (docs/method.md "Spectral analysis and the output
// filter"), measured on the DUT by its loop test (docs/can-protocol.md "Loop test"), never taken
// from a model. Two phases, as the recordings and their analysis are:
//   loop          the DUT steps a test torque inside its loop; the rig keeps each step's
//                 response at the loop rate in the run folder (kLoopTestFile, every value as
//                 the DUT sent it) and its description in the state (LoopRecord, with the
//                 file's CRC-32);
//   loop-figures  reads the settling time and the 0.5-level bandwidth of the filtered output y,
//                 with 95 % intervals over the steps, off that file (Phase::from_records: a
//                 resume computes them again and never measures the DUT twice).
// A DUT without a loop test leaves both values null with the reason, unless the hardware file
// names the DUT type's design model ([dut.design]): then its figures, labelled "design model",
// computed by design/ for the profile's filter.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "procedures/acceptance/loop_record.hpp"
#include "procedures/acceptance/profile.hpp"
#include "procedures/acceptance/state.hpp"
#include "rig/core/dut_link.hpp"
#include "rig/executive/executive.hpp"

namespace rig::acceptance {

void phase_loop_test(PhaseContext& ctx, const Profile& p, DutState& st);     // `loop`: needs the DUT
void phase_loop_figures(PhaseContext& ctx, const Profile& p, DutState& st);  // `loop-figures`: from the records

// The hardware file's optional [dut.design] ([dut.design.loop] and [dut.design.regulator], the
// keys of design/loop_params.hpp; absent keys keep design/'s defaults): nullopt without it.
// Unknown keys and values out of range => ConfigError naming file:line.
std::optional<Profile::DesignModel> read_design_model(const toml::table& dut);

// Figures of a loop test's records as analysis.json's "loop" carries them (the report draws its
// step and amplitude curves), with the two passport values' intervals.
nlohmann::json loop_test_figures(const LoopTestResponse& r);

// The settling time's note where a step's overshoot lies within half a point of the settling band
// (the figure jumps there between the rise and the peak), from loop_test_figures' `per_step`;
// "" where none does.
std::string settling_near_the_band(const nlohmann::json& per_step);

}  // namespace rig::acceptance
