#include "analysis/rms.hpp"

#include <cmath>

namespace rig::analysis {

double rms(std::span<const double> x) {
  if (x.empty()) return 0;
  double s = 0;
  for (double v : x) s += v * v;
  return std::sqrt(s / static_cast<double>(x.size()));
}

}  // namespace rig::analysis
