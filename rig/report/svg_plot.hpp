// SVG figures built as strings (no I/O, no plotting library): the log-log Allan plot in
// the style of the paper's Fig. 2 (bounds as error bars, the weighted-fit terms as slope
// lines, the paper's polynomial and segment middles tau_cp) and the PSD with its peaks.
#pragma once
#include <span>
#include <string>

#include "analysis/allan.hpp"
#include "analysis/noise_terms.hpp"
#include "analysis/psd.hpp"

namespace rig::report {

std::string allan_svg(std::span<const analysis::DevPoint> pts, const analysis::NoiseTerms& terms, const std::string& title,
                      const std::string& unit = "g");
std::string psd_svg(const analysis::Psd& p, std::span<const analysis::Peak> peaks, const std::string& title, const std::string& unit = "g");

}  // namespace rig::report
