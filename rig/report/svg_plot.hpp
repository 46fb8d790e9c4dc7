// The Allan and PSD figures, built from the analysis' JSON views (analysis/json.hpp: the
// shapes of analysis.json's allan.x/psd.x and of `rig analyze --json`), for report.html and
// `rig analyze --svg` alike: one plotter (svg.hpp), and the curves drawn as the analysis wrote
// them (noise_terms.curves), never recomputed here.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rig/report/json_read.hpp"
#include "rig/report/svg.hpp"

namespace rig::report {

// OADEV points (`dev_to_json`) with their bounds at `confidence` (NaN: level not known), and,
// when `noise_terms` (`noise_terms_to_json`) is given, each identified term's curve labelled
// in the passport's per-hour units, the weighted fit's sum, the paper's polynomial and its
// segments, and tau_cp with B. `color` is the points' colour.
Plot allan_plot(const nlohmann::json& oadev, const nlohmann::json* noise_terms, double confidence,
                const std::string& id, const std::string& title, const std::string& color);

// The Welch PSD (`psd_to_json`) with its peaks circled and labelled in Hz. With the sampling
// rate `rate_hz` known (NaN: not known), a peak at f below the Nyquist frequency is labelled
// "f Hz or fs−f Hz": a line at fs − f (above Nyquist) folds onto f when sampled, and the record
// alone cannot tell which of the two is real (docs/analysis.md "PSD peaks and aliases").
Plot psd_plot(const nlohmann::json& psd, const std::string& id, const std::string& title, const std::string& color,
              double rate_hz = kNaN);

// A peak's label: "f Hz", or "f Hz or fs−f Hz" when the rate is known and fs − f is another
// frequency (0 < f < fs/2).
std::string peak_label(double f_hz, double rate_hz);

// The caption's sentence on aliases for a PSD sampled at `rate_hz`; "" when the rate is unknown.
std::string alias_note(double rate_hz);

// "f1 Hz, f2 Hz, …" of the peaks whose labels `to_svg` placed (in the plot's marker order).
std::string labelled_peaks(const Plot& p, const std::vector<bool>& labelled);

}  // namespace rig::report
