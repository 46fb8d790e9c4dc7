// Test helpers: the Stable32 reference sets in tests/data/allan-reference (plain or gzip text).
#pragma once
#include <string>
#include <vector>

namespace rig::analysis::testing {

// Numbers, one per line, '#' comments; ".gz" files are inflated with zlib.
std::vector<double> read_values(const std::string& path);

struct S32Row {
  std::size_t af = 0, terms = 0;
  int alpha = 0;
  double lo = 0, dev = 0, hi = 0;
};
// A Stable32 table: AF Tau # Alpha MinSigma Sigma MaxSigma.
std::vector<S32Row> read_table(const std::string& path);

std::string ref_path(const std::string& rel);

}  // namespace rig::analysis::testing
