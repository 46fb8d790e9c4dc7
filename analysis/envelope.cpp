#include "analysis/envelope.hpp"

#include <algorithm>

namespace rig::analysis {

Envelope block_envelope(std::span<const double> x, double rate_hz, std::size_t max_blocks) {
  Envelope e;
  if (x.empty() || !(rate_hz > 0) || max_blocks == 0) return e;
  const std::size_t len = (x.size() + max_blocks - 1) / max_blocks;
  e.block_s = static_cast<double>(len) / rate_hz;
  for (std::size_t a = 0; a < x.size(); a += len) {
    const std::span<const double> b = x.subspan(a, std::min(len, x.size() - a));
    double sum = 0;
    for (double v : b) sum += v;
    const auto [lo, hi] = std::minmax_element(b.begin(), b.end());
    e.t_s.push_back((static_cast<double>(a) + static_cast<double>(b.size()) / 2) / rate_hz);
    e.mean.push_back(sum / static_cast<double>(b.size()));
    e.min.push_back(*lo);
    e.max.push_back(*hi);
  }
  return e;
}

}  // namespace rig::analysis
