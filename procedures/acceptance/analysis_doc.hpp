// analysis.json (rig.analysis/1, read by the report): the procedure state accumulated by
// the phases, and the loop figures' JSON view.
#pragma once
#include <nlohmann/json.hpp>

#include "design/loop_figures.hpp"

namespace rig::acceptance {

nlohmann::json loop_to_json(const design::LoopFigures& f);

// analysis.json from the procedure state accumulated by the phases.
nlohmann::json analysis_document(const nlohmann::json& state);

}  // namespace rig::acceptance
