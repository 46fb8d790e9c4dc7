// analysis.json (rig.analysis/1, read by the report): the procedure state accumulated by
// the phases.
#pragma once
#include <nlohmann/json.hpp>

#include "procedures/acceptance/state.hpp"

namespace rig::acceptance {

// analysis.json from one DUT's state: "runs" (array by index), "bias", "in_run" (with
// "blocks"), "raw", the allan phase's keys (allan, psd, timeseries) at the top, "loop", "dut".
// Recorded captures carry one set of keys everywhere (capture, n, lost, gaps, duplicates,
// attempts, mean_g, mean_y_g).
nlohmann::json analysis_document(const DutState& state);

}  // namespace rig::acceptance
