// SVG figures built as strings (no I/O, no plotting library): the log-log Allan plot in
// the style of the paper's Fig. 2 (bounds as error bars, the weighted-fit terms as slope
// lines, the paper's polynomial and segment middles tau_cp) and the PSD with its peaks.
#pragma once
#include <span>
#include <string>

#include "procedures/analysis/allan.hpp"
#include "procedures/analysis/noise_terms.hpp"
#include "procedures/analysis/psd.hpp"

namespace rig::analysis {

std::string allan_svg(std::span<const DevPoint> pts, const NoiseTerms& terms, const std::string& title,
                      const std::string& unit = "g");
std::string psd_svg(const Psd& p, std::span<const Peak> peaks, const std::string& title, const std::string& unit = "g");

}  // namespace rig::analysis
