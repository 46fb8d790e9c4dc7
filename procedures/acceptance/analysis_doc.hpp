// analysis.json (rig.analysis/1, read by the report): the procedure state accumulated by
// the phases.
#pragma once
#include <nlohmann/json.hpp>

namespace rig::acceptance {

// analysis.json from the procedure state accumulated by the phases.
nlohmann::json analysis_document(const nlohmann::json& state);

}  // namespace rig::acceptance
