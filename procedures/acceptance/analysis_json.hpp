// JSON views of the analysis results: analysis.json (rig.analysis/1, read by
// the report) and the `noise_terms` object shared with `rig analyze --json`.
#pragma once
#include <span>
#include <vector>

#include <nlohmann/json.hpp>

#include "plant/dut/loop_figures.hpp"
#include "procedures/analysis/allan.hpp"
#include "procedures/analysis/noise_terms.hpp"
#include "procedures/analysis/psd.hpp"

namespace rig::acceptance {

nlohmann::json dev_to_json(std::span<const analysis::DevPoint> dev);
nlohmann::json noise_terms_to_json(const analysis::NoiseTerms& nt);
nlohmann::json psd_to_json(const analysis::Psd& psd, const std::vector<analysis::Peak>& peaks);
nlohmann::json loop_to_json(const plant::LoopFigures& f);

// analysis.json from the procedure state accumulated by the phases.
nlohmann::json analysis_document(const nlohmann::json& state);

}  // namespace rig::acceptance
