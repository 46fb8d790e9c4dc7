// The median the fits read a scale from (no I/O, no state).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace rig::analysis {

// The upper median of v (its (n/2)-th smallest value, 0-based); v non-empty.
inline double upper_median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// The binary exponent e of the upper median (median = f 2^e, f in [0.5, 1), frexp's), 0 for an
// empty v: dividing by 2^e brings the values near 1 exactly (a power of two), so a fit made there
// and scaled back by 2^e is the same in any unit that is a power of two, and never under- or
// overflows for values of any magnitude a double holds.
inline int median_exponent(std::vector<double> v) {
  int e = 0;
  if (!v.empty()) std::frexp(upper_median(std::move(v)), &e);
  return e;
}

}  // namespace rig::analysis
