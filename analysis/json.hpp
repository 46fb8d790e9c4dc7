// JSON views of the analysis results (nlohmann::json): the deviation table, the noise terms
// and the PSD, in the shapes of CONTRACTS' `rig analyze --json`, shared by `rig analyze` and
// the procedure's analysis.json. Formatting only: no I/O.
#pragma once
#include <span>
#include <vector>

#include <nlohmann/json.hpp>

#include <string>

#include "analysis/allan.hpp"
#include "analysis/envelope.hpp"
#include "analysis/noise_terms.hpp"
#include "analysis/psd.hpp"
#include "analysis/theo.hpp"

namespace rig::analysis {

// bounds = false (rig analyze --no-bounds): lo, hi, edf, alpha and edf_alpha are null.
nlohmann::json dev_to_json(std::span<const DevPoint> dev, bool bounds = true);
// A long-tau statistic (theo.hpp): dev_to_json's fields plus dev_raw, stride and estimator.
nlohmann::json long_tau_to_json(std::span<const LongTauPoint> pts, bool bounds = true);
nlohmann::json noise_terms_to_json(const NoiseTerms& nt);
nlohmann::json psd_to_json(const Psd& psd, const std::vector<Peak>& peaks);
// Both channels' block envelopes (same record, same blocks) and what the record is.
nlohmann::json envelope_to_json(const Envelope& x, const Envelope& y, const std::string& note);

}  // namespace rig::analysis
