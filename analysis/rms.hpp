// The RMS error, criterion 1 of the output filter (METHOD.md "Spectral analysis and the
// output filter"). The filter itself (response, design, W_f(z), criterion 2) is design/filter.hpp.
#pragma once
#include <span>

namespace rig::analysis {

// sqrt(mean(x^2)), the paper's RMS error criterion; 0 for an empty x.
double rms(std::span<const double> x);

}  // namespace rig::analysis
